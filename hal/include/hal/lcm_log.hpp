// LCM log files (the format of lcm-logger / lcm-logplayer / lcm_eventlog): a sequence of events
//
//   sync word 0xEDA1DA01 (uint32) | event number (int64) | timestamp [us] (int64) |
//   channel length (int32) | data length (int32) | channel (ASCII, no terminator) | data
//
// all integers big-endian. The format has no checksum: corrupted bytes inside an event's data
// are found only when the message no longer decodes or its values are rejected (lcm_convert.hpp).
//
// WHY OUR OWN READER. LCM's lcm_eventlog_read_next_event() trusts the length fields: it
// allocates whatever the data length says and, when that read comes up short, returns NULL, which
// every LCM tool takes for the end of the log. Measured with Debian's liblcm 1.3.1 on a
// three-event log whose second data length was overwritten with 0x7ffffff0: it returned the
// first event and then NULL, so the third (intact) event was lost (the probe is in
// tests/unit/test_lcm_log.cpp, LcmLog.LcmEventlogLosesEventsAfterACorruptLength). This reader
// instead checks every header (channel length 1..kMaxChannelLength, printable channel name, data
// length <= max_data_bytes and within the file, and that the next event starts where this one
// ends with the next event number, else that no plausible event starts inside this one: a length
// corrupted to swallow whole events is caught), resynchronises on the next sync word after any
// rejection, counts every rejection with its reason and file offset, and never reads outside the
// file. The file is memory-mapped
// (read-only), so an event is a view into the mapping: no allocation per event, and logs much
// larger than memory work. Do not read a log that another process is still truncating.
// The writer is equally small and writes the exact LCM format; a test reads our logs with LCM's
// own reader (lcm-logplayer and the lcm_eventlog C API).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "hal/output_file.hpp"

namespace hal {

inline constexpr std::uint32_t kLcmLogSyncWord = 0xEDA1DA01u;
inline constexpr std::size_t kLcmLogHeaderBytes = 28;  ///< sync + event number + timestamp + 2 lengths
/// Longest channel name accepted (LCM itself allows 63 on udpm; its newer log reader < 1000).
inline constexpr std::uint32_t kLcmMaxChannelLength = 255;

enum class LcmLogStatus : std::uint8_t {
  kOk = 0,
  kEndOfLog,     ///< no further event
  kOpenFailed,   ///< the file could not be opened / mapped / created
  kNotOpen,      ///< no file open
  kBadChannel,   ///< writer: empty, too long or non-printable channel name
  kTooLarge,     ///< writer: data longer than an int32 length can say
  kWriteFailed,  ///< writer: the OS refused the bytes (disk full, I/O error)
};

const char* to_string(LcmLogStatus s);

/// Why the reader skipped bytes of a log.
enum class LcmLogRejection : std::uint8_t {
  kTruncatedEvent = 0,  ///< the last event is cut short by the end of the file
  kBadChannelLength,    ///< channel length 0 or above kLcmMaxChannelLength
  kBadDataLength,       ///< data length above the limit, or it runs past the next event / the file end
  kBadChannelName,      ///< a channel byte outside printable ASCII
  kNoSync,              ///< bytes that are not part of any event (lost sync, garbage)
  kCount
};

const char* to_string(LcmLogRejection r);

struct LcmLogRejectionRecord {
  std::uint64_t offset = 0;  ///< file offset of the skipped bytes
  std::uint64_t bytes = 0;   ///< how many bytes were skipped
  LcmLogRejection reason = LcmLogRejection::kNoSync;
};

struct LcmLogReadStats {
  std::uint64_t events = 0;  ///< good events returned
  std::uint64_t rejections[static_cast<int>(LcmLogRejection::kCount)] = {};
  std::uint64_t bytes_skipped = 0;
  /// The first kMaxRecords rejections in file order (all of them are counted above).
  std::vector<LcmLogRejectionRecord> records;
  static constexpr std::size_t kMaxRecords = 1000;

  std::uint64_t count(LcmLogRejection r) const { return rejections[static_cast<int>(r)]; }
  std::uint64_t total_rejections() const;
};

/// One event: views into the reader's mapping, valid until the reader is closed or destroyed.
struct LcmLogEvent {
  std::int64_t event_number = 0;
  std::int64_t timestamp_us = 0;
  std::string_view channel;
  const std::uint8_t* data = nullptr;
  std::size_t data_len = 0;
  std::uint64_t offset = 0;  ///< file offset of the sync word
};

class LcmLogReader {
 public:
  LcmLogReader() = default;
  ~LcmLogReader();
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;

  /// Maps the file. max_data_bytes bounds a single event's data (absurd lengths are rejected).
  LcmLogStatus open(const std::string& path, std::size_t max_data_bytes = 64u << 20);
  void close();
  /// The next good event (kOk) or kEndOfLog. Rejections on the way are counted in stats().
  LcmLogStatus next(LcmLogEvent& ev);
  /// Back to the first byte (stats are reset).
  void rewind();

  const LcmLogReadStats& stats() const { return stats_; }
  std::uint64_t file_size() const { return size_; }
  const std::string& error() const { return error_; }

 private:
  bool sync_at(std::uint64_t pos) const;
  std::uint64_t find_sync(std::uint64_t from, std::uint64_t limit) const;
  /// Header at pos (sync already checked) looks like a complete, plausible event.
  bool plausible_event(std::uint64_t pos) const;
  void reject(LcmLogRejection why, std::uint64_t offset, std::uint64_t bytes);

  bool open_ = false;
  const std::uint8_t* base_ = nullptr;
  std::uint64_t size_ = 0;
  std::uint64_t pos_ = 0;
  std::size_t max_data_ = 0;
  LcmLogReadStats stats_;
  std::string error_;
};

class LcmLogWriter {
 public:
  LcmLogWriter() = default;
  ~LcmLogWriter();
  LcmLogWriter(const LcmLogWriter&) = delete;
  LcmLogWriter& operator=(const LcmLogWriter&) = delete;

  /// Starts the file through hal::OutputFile: the events go to a temporary file beside `path`,
  /// which close() renames over it (an existing file stays as it was until then).
  LcmLogStatus open(const std::string& path);
  /// Appends one event; the event number counts from 0. No allocation.
  LcmLogStatus write(const char* channel, const void* data, std::size_t len, std::int64_t timestamp_us);
  LcmLogStatus flush();
  /// Flushes, fsyncs, closes and renames into place; kWriteFailed (error()) on any failure.
  LcmLogStatus close();
  /// Drops the log: the temporary file is removed, `path` is left as it was.
  void abort();
  bool is_open() const { return file_.is_open(); }
  /// The first failure: the file's name and the errno text.
  const std::string& error() const { return file_.error(); }
  std::uint64_t events_written() const { return events_; }
  std::uint64_t write_failures() const { return failures_; }
  const std::string& path() const { return path_; }

 private:
  OutputFile file_;
  std::uint64_t events_ = 0;
  std::uint64_t failures_ = 0;
  std::string path_;
};

/// A channel name the writer accepts: 1..kLcmMaxChannelLength printable ASCII characters.
bool lcm_channel_name_ok(std::string_view channel);

}  // namespace hal
