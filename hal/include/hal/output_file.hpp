// Output files written so that nothing is lost and nothing fails silently (docs/faults.md).
//
// The one discipline for every file the project writes (CLI outputs, LCM logs, candump logs,
// CSV/JSON/markdown reports):
//  - check_outputs(): before anything is opened for writing, an output that is the same file as
//    an input (same st_dev/st_ino after following links), that lies inside an input directory, or
//    that is the same file as another output of the same command, is refused with a message naming
//    both paths;
//  - OutputFile: the bytes go to an unnamed file in the target's directory (O_TMPFILE); commit()
//    flushes and fsyncs it and links it in: as the target when there is none, else under a
//    temporary name renamed over the target (atomic: same directory). Where O_TMPFILE or /proc is
//    missing, a named temporary file ".NAME.sdins-tmp.PID.N" beside the target is written and
//    renamed instead. Until commit() the target keeps its old contents (or does not exist): a
//    failure, an exception, an interrupt or a SIGKILL leaves the old file or nothing, never half a
//    file, and (with O_TMPFILE) no temporary file either.
//    An existing target that is not a regular file (a device such as /dev/null or /dev/full, a
//    FIFO) is written in place, since it cannot be renamed over;
//  - every write, flush, fsync, close and rename is checked; the first failure is kept with the
//    file's name and the errno text (error()), and commit() returns false.
// A temporary file is registered until commit()/abort() so that remove_pending_outputs() (async-
// signal-safe: unlink() only) can delete it from a signal handler before the process exits. Only
// a named temporary file can outlive a SIGKILL: the fallback's whole life, or the microseconds
// between link and rename when an existing target is replaced (the target is untouched either way).
//
// Host-side only (hal's POSIX part): no exceptions; status by bool + error().
#pragma once

#include <cstddef>
#include <cstdint>
#include <ostream>
#include <streambuf>
#include <string>
#include <string_view>
#include <vector>

namespace hal {

/// Empty when every output may be written; otherwise why not (names the paths). Inputs may be
/// files or directories; an input that does not exist is ignored (its reader reports it).
std::string check_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

class OutputFile {
 public:
  OutputFile();
  ~OutputFile();  ///< abort() unless committed
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// Creates the temporary file beside `path` (links followed: the file a link names is the one
  /// replaced). false (error() set) when it cannot be created.
  bool open(const std::string& path);
  /// Buffered append; false once any write failed (error() names the file and errno).
  bool write(const void* data, std::size_t n);
  bool write(std::string_view s) { return write(s.data(), s.size()); }
  /// Text output through the same buffer and error tracking.
  std::ostream& stream() { return os_; }
  /// Pushes the buffer to the OS (not fsync). false on a write error.
  bool flush();
  /// flush + fsync + close + rename over the target. false (error() set) on any failure, in
  /// which case the temporary file is removed and the target is left as it was.
  bool commit();
  /// Closes and removes the temporary file; the target is untouched.
  void abort();

  bool is_open() const { return fd_ >= 0; }
  bool failed() const { return !error_.empty(); }
  const std::string& path() const { return path_; }
  const std::string& error() const { return error_; }
  std::uint64_t bytes_written() const { return bytes_; }

 private:
  class Buf : public std::streambuf {
   public:
    explicit Buf(OutputFile& f) : f_(f) {}
   protected:
    int_type overflow(int_type c) override;
    std::streamsize xsputn(const char* s, std::streamsize n) override;
    int sync() override;
   private:
    OutputFile& f_;
  };
  bool drain();
  std::string temporary_name() const;
  bool link_anonymous();
  void fail(const char* what, int err);
  void release_slot();

  int fd_ = -1;
  bool in_place_ = false;  ///< writing a non-regular target directly
  bool anonymous_ = false; ///< fd_ is an unnamed O_TMPFILE file, linked in by commit()
  int slot_ = -1;          ///< registry slot of the temporary file
  std::string path_;       ///< as given
  std::string target_;     ///< the file replaced (links resolved)
  std::string tmp_;
  std::string error_;
  std::vector<char> buf_;
  std::size_t used_ = 0;
  std::uint64_t bytes_ = 0;
  Buf sbuf_;
  std::ostream os_;
};

/// Writes a whole file through OutputFile. false with `error` set on any failure.
bool write_file_atomic(const std::string& path, std::string_view content, std::string& error);

/// Whether OutputFile tries an unnamed O_TMPFILE file first (default true). Tests switch it off to
/// exercise the named-temporary fallback that file systems without O_TMPFILE get.
void set_unnamed_temporaries(bool on) noexcept;

/// Removes every registered temporary file (async-signal-safe: unlink only). For signal handlers.
void remove_pending_outputs() noexcept;

/// Every output this process put in place (commit() succeeded), as the paths were given, in commit
/// order; and outputs written by other means (e.g. a plot script's figures) added by note_output().
/// tools::RunDirectory names a run's outputs from it (docs/faults.md, "run directories").
std::vector<std::string> committed_outputs();
void note_output(const std::string& path);

}  // namespace hal
