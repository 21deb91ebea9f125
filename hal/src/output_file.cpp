#include "hal/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <mutex>
#include <cstring>
#include <filesystem>
#include <system_error>

namespace hal {
namespace {

namespace fs = std::filesystem;

// ---- registry of temporary files, for remove_pending_outputs() from a signal handler ----
constexpr int kSlots = 64;
constexpr std::size_t kSlotPath = 4096;
struct Slot {
  std::atomic<int> used{0};  // 0 free, 1 claimed (path being written), 2 registered
  char path[kSlotPath] = {};
};
std::array<Slot, kSlots> g_slots;
std::atomic<unsigned> g_counter{0};
std::atomic<bool> g_unnamed{true};

int register_tmp(const std::string& p) {
  if (p.size() + 1 > kSlotPath) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (g_slots[static_cast<std::size_t>(i)].used.compare_exchange_strong(expected, 1)) {
      std::memcpy(g_slots[static_cast<std::size_t>(i)].path, p.c_str(), p.size() + 1);
      g_slots[static_cast<std::size_t>(i)].used.store(2, std::memory_order_release);
      return i;
    }
  }
  return -1;  // more than kSlots files open at once: still written, just not removed on a signal
}

struct Identity {
  bool exists = false;
  bool is_dir = false;
  dev_t dev = 0;
  ino_t ino = 0;
  fs::path resolved;  ///< canonical when it exists, else weakly canonical
};

Identity identify(const std::string& p) {
  Identity id;
  std::error_code ec;
  struct stat st {};
  if (::stat(p.c_str(), &st) == 0) {
    id.exists = true;
    id.is_dir = S_ISDIR(st.st_mode);
    id.dev = st.st_dev;
    id.ino = st.st_ino;
    id.resolved = fs::canonical(p, ec);
    if (ec) id.resolved = fs::absolute(p, ec);
  } else {
    id.resolved = fs::weakly_canonical(fs::absolute(p, ec), ec);
  }
  return id;
}

bool same(const Identity& a, const Identity& b) {
  if (a.exists && b.exists) return a.dev == b.dev && a.ino == b.ino;
  return !a.exists && !b.exists && a.resolved == b.resolved;
}

/// `inner` lies below directory `dir` (both resolved).
bool inside(const fs::path& inner, const fs::path& dir) {
  auto d = dir.begin();
  auto i = inner.begin();
  for (; d != dir.end(); ++d, ++i) {
    if (d->empty()) continue;  // trailing separator
    if (i == inner.end() || *i != *d) return false;
  }
  return i != inner.end();
}

}  // namespace

std::string check_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs) {
  std::vector<Identity> in;
  in.reserve(inputs.size());
  for (const std::string& p : inputs) in.push_back(identify(p));
  std::vector<Identity> out;
  for (const std::string& o : outputs) {
    if (o.empty()) {
      out.emplace_back();
      continue;
    }
    const Identity oid = identify(o);
    for (std::size_t k = 0; k < inputs.size(); ++k) {
      if (inputs[k].empty() || !in[k].exists) continue;
      if (same(oid, in[k]))
        return "output " + o + " is the input " + inputs[k] + " (the same file): refusing to overwrite an input";
      if (in[k].is_dir && inside(oid.resolved, in[k].resolved))
        return "output " + o + " lies inside the input directory " + inputs[k] + ": refusing to write into an input";
    }
    for (std::size_t k = 0; k < out.size(); ++k) {
      if (outputs[k].empty()) continue;
      if (same(oid, out[k])) return "outputs " + outputs[k] + " and " + o + " are the same file";
    }
    out.push_back(oid);
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
OutputFile::OutputFile() : sbuf_(*this), os_(&sbuf_) {}

OutputFile::~OutputFile() { abort(); }

void OutputFile::fail(const char* what, int err) {
  if (!error_.empty()) return;
  error_ = path_ + ": " + what + (err != 0 ? std::string(": ") + std::strerror(err) : std::string());
  os_.setstate(std::ios::badbit);
}

void OutputFile::release_slot() {
  if (slot_ >= 0) g_slots[static_cast<std::size_t>(slot_)].used.store(0, std::memory_order_release);
  slot_ = -1;
}

bool OutputFile::open(const std::string& path) {
  abort();
  path_ = path;
  error_.clear();
  bytes_ = 0;
  used_ = 0;
  in_place_ = false;
  os_.clear();
  if (path.empty()) {
    error_ = "empty output path";
    os_.setstate(std::ios::badbit);
    return false;
  }
  std::error_code ec;
  // Follow links: replace the file a link points to, not the link.
  fs::path target = path;
  if (fs::is_symlink(target, ec)) {
    const fs::path c = fs::weakly_canonical(target, ec);
    if (ec) {  // a loop of links: refused (it used to replace the link itself with a regular file)
      target_ = path;
      fail("is a symbolic link that does not resolve", ec.value());
      return false;
    }
    target = c;
  }
  target_ = target.string();
  struct stat st {};
  const bool exists = ::stat(target_.c_str(), &st) == 0;
  if (exists && S_ISDIR(st.st_mode)) {
    fail("is a directory", 0);
    return false;
  }
  if (exists && !S_ISREG(st.st_mode)) {
    // A device or FIFO: cannot be renamed over; written in place.
    fd_ = ::open(target_.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY);
    if (fd_ < 0) {
      fail("cannot open for writing", errno);
      return false;
    }
    in_place_ = true;
  } else {
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    // First choice: an unnamed file in the target's directory (O_TMPFILE), linked in by commit():
    // until then it has no name, so nothing is left behind whatever ends the process, SIGKILL and
    // power cuts included. Needs /proc (commit links it through /proc/self/fd) and a file system
    // that supports it (ext4, xfs, btrfs, tmpfs); otherwise a named temporary file.
    anonymous_ = false;
    if (g_unnamed.load(std::memory_order_relaxed) && ::access("/proc/self/fd", X_OK) == 0) {
      fd_ = ::open(dir.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
      anonymous_ = fd_ >= 0;
    }
    for (int attempt = 0; attempt < 100 && fd_ < 0; ++attempt) {
      tmp_ = temporary_name();
      fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd_ < 0 && errno != EEXIST) break;
    }
    if (fd_ < 0) {
      const int e = errno;
      tmp_.clear();
      fail(("cannot create a file in " + dir.string()).c_str(), e);
      return false;
    }
    if (exists) (void)::fchmod(fd_, st.st_mode & 07777);  // keep the replaced file's permissions
    if (!anonymous_) slot_ = register_tmp(tmp_);
  }
  if (buf_.empty()) buf_.resize(64u << 10);
  return true;
}

std::string OutputFile::temporary_name() const {
  const fs::path target = target_;
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  return (dir / ("." + target.filename().string() + ".sdins-tmp." + std::to_string(::getpid()) + "." +
                 std::to_string(g_counter.fetch_add(1))))
      .string();
}

bool OutputFile::link_anonymous() {
  // The unnamed file gets its name: the target itself when there is none yet (atomic: linkat never
  // replaces), else a temporary name renamed over the target (microseconds during which a SIGKILL
  // would leave that name behind; a SIGINT/SIGTERM handler removes it).
  const std::string self = "/proc/self/fd/" + std::to_string(fd_);
  if (::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, target_.c_str(), AT_SYMLINK_FOLLOW) == 0) return true;
  if (errno != EEXIST) {
    fail("cannot link the written file to its name", errno);
    return false;
  }
  for (int attempt = 0; attempt < 100; ++attempt) {
    tmp_ = temporary_name();
    slot_ = register_tmp(tmp_);
    if (::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, tmp_.c_str(), AT_SYMLINK_FOLLOW) == 0) return true;
    const int e = errno;
    release_slot();
    tmp_.clear();
    if (e != EEXIST) {
      fail("cannot link the written file beside it", e);
      return false;
    }
  }
  fail("cannot find a free temporary name beside it", EEXIST);
  return false;
}

bool OutputFile::drain() {
  std::size_t off = 0;
  while (off < used_) {
    const ssize_t n = ::write(fd_, buf_.data() + off, used_ - off);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write failed", errno);
      used_ = 0;
      return false;
    }
    off += static_cast<std::size_t>(n);
  }
  used_ = 0;
  return true;
}

bool OutputFile::write(const void* data, std::size_t n) {
  if (fd_ < 0) {
    if (error_.empty()) fail("not open", 0);
    return false;
  }
  if (!error_.empty()) return false;
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    if (used_ == buf_.size() && !drain()) return false;
    const std::size_t k = std::min(n, buf_.size() - used_);
    std::memcpy(buf_.data() + used_, p, k);
    used_ += k;
    p += k;
    n -= k;
    bytes_ += k;
  }
  return true;
}

bool OutputFile::flush() {
  if (fd_ < 0) return false;
  if (!error_.empty()) return false;
  return drain();
}

bool OutputFile::commit() {
  if (fd_ < 0) {
    if (error_.empty()) fail("not open", 0);
    return false;
  }
  bool ok = error_.empty() && drain();
  // fsync: a regular file only (devices and FIFOs may refuse it).
  if (ok && !in_place_ && ::fsync(fd_) != 0) {
    fail("fsync failed", errno);
    ok = false;
  }
  if (in_place_) {
    if (::close(fd_) != 0 && ok) {
      fail("close failed", errno);
      ok = false;
    }
    fd_ = -1;
    return ok;
  }
  if (ok && anonymous_) ok = link_anonymous();
  if (fd_ >= 0 && ::close(fd_) != 0 && ok) {
    fail("close failed", errno);
    ok = false;
  }
  fd_ = -1;
  if (ok && !tmp_.empty() && ::rename(tmp_.c_str(), target_.c_str()) != 0) {
    fail(("cannot rename " + tmp_ + " over it").c_str(), errno);
    ok = false;
  }
  if (!ok && !tmp_.empty()) ::unlink(tmp_.c_str());
  release_slot();
  tmp_.clear();
  if (ok) {
    note_output(path_);
    // Make the rename itself durable.
    std::error_code ec;
    const fs::path dir = fs::path(target_).has_parent_path() ? fs::path(target_).parent_path() : fs::path(".");
    const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
      (void)::fsync(dfd);
      ::close(dfd);
    }
  }
  return ok;
}

void OutputFile::abort() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!tmp_.empty()) ::unlink(tmp_.c_str());
  tmp_.clear();
  release_slot();
  used_ = 0;
}

OutputFile::Buf::int_type OutputFile::Buf::overflow(int_type c) {
  if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
  const char ch = traits_type::to_char_type(c);
  return f_.write(&ch, 1) ? c : traits_type::eof();
}

std::streamsize OutputFile::Buf::xsputn(const char* s, std::streamsize n) {
  return f_.write(s, static_cast<std::size_t>(n)) ? n : 0;
}

int OutputFile::Buf::sync() { return f_.flush() ? 0 : -1; }

bool write_file_atomic(const std::string& path, std::string_view content, std::string& error) {
  OutputFile f;
  if (!f.open(path) || !f.write(content) || !f.commit()) {
    error = f.error();
    return false;
  }
  return true;
}

void set_unnamed_temporaries(bool on) noexcept { g_unnamed.store(on, std::memory_order_relaxed); }

namespace {
std::mutex g_committed_mu;
std::vector<std::string> g_committed;
}  // namespace

void note_output(const std::string& path) {
  const std::lock_guard<std::mutex> lock(g_committed_mu);
  g_committed.push_back(path);
}

std::vector<std::string> committed_outputs() {
  const std::lock_guard<std::mutex> lock(g_committed_mu);
  return g_committed;
}

void remove_pending_outputs() noexcept {
  for (Slot& s : g_slots)
    if (s.used.load(std::memory_order_acquire) == 2) ::unlink(s.path);
}

}  // namespace hal
