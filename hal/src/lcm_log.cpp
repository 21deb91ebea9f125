#include "hal/lcm_log.hpp"

#include "hal/input_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace hal {
namespace {

std::uint32_t be32(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) |
         (static_cast<std::uint32_t>(p[2]) << 8) | static_cast<std::uint32_t>(p[3]);
}
std::uint64_t be64(const std::uint8_t* p) {
  return (static_cast<std::uint64_t>(be32(p)) << 32) | be32(p + 4);
}
void put32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 3; i >= 0; --i) {
    p[i] = static_cast<std::uint8_t>(v & 0xffu);
    v >>= 8;
  }
}
void put64(std::uint8_t* p, std::uint64_t v) {
  put32(p, static_cast<std::uint32_t>(v >> 32));
  put32(p + 4, static_cast<std::uint32_t>(v & 0xffffffffu));
}
bool channel_byte_ok(std::uint8_t c) { return c >= 0x20 && c <= 0x7e; }

}  // namespace

const char* to_string(LcmLogStatus s) {
  switch (s) {
    case LcmLogStatus::kOk: return "ok";
    case LcmLogStatus::kEndOfLog: return "end_of_log";
    case LcmLogStatus::kOpenFailed: return "open_failed";
    case LcmLogStatus::kNotOpen: return "not_open";
    case LcmLogStatus::kBadChannel: return "bad_channel";
    case LcmLogStatus::kTooLarge: return "too_large";
    case LcmLogStatus::kWriteFailed: return "write_failed";
  }
  return "unknown";
}

const char* to_string(LcmLogRejection r) {
  switch (r) {
    case LcmLogRejection::kTruncatedEvent: return "truncated_event";
    case LcmLogRejection::kBadChannelLength: return "bad_channel_length";
    case LcmLogRejection::kBadDataLength: return "bad_data_length";
    case LcmLogRejection::kBadChannelName: return "bad_channel_name";
    case LcmLogRejection::kNoSync: return "no_sync";
    case LcmLogRejection::kCount: break;
  }
  return "unknown";
}

std::uint64_t LcmLogReadStats::total_rejections() const {
  std::uint64_t n = 0;
  for (std::uint64_t r : rejections) n += r;
  return n;
}

bool lcm_channel_name_ok(std::string_view channel) {
  if (channel.empty() || channel.size() > kLcmMaxChannelLength) return false;
  for (char c : channel)
    if (!channel_byte_ok(static_cast<std::uint8_t>(c))) return false;
  return true;
}

// ---------------------------------------------------------------------------------------------
LcmLogReader::~LcmLogReader() { close(); }

LcmLogStatus LcmLogReader::open(const std::string& path, std::size_t max_data_bytes) {
  close();
  stats_ = LcmLogReadStats{};
  error_.clear();
  // O_NONBLOCK: a FIFO must not block the open (it is refused below: regular files only).
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    error_ = path + ": " + std::strerror(errno);
    return LcmLogStatus::kOpenFailed;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    error_ = check_input_file(path, ~0ull);  // names the kind (device, FIFO, directory)
    if (error_.empty()) error_ = path + ": not a regular file";
    ::close(fd);
    return LcmLogStatus::kOpenFailed;
  }
  size_ = static_cast<std::uint64_t>(st.st_size);
  if (size_ > 0) {
    void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      error_ = path + ": mmap: " + std::strerror(errno);
      ::close(fd);
      size_ = 0;
      return LcmLogStatus::kOpenFailed;
    }
    ::madvise(p, size_, MADV_SEQUENTIAL);
    base_ = static_cast<const std::uint8_t*>(p);
  }
  ::close(fd);
  open_ = true;
  pos_ = 0;
  // The length field is an int32: nothing larger can be a valid event.
  max_data_ = max_data_bytes < 0x7fffffffu ? max_data_bytes : 0x7fffffffu;
  return LcmLogStatus::kOk;
}

void LcmLogReader::close() {
  if (base_ != nullptr) ::munmap(const_cast<std::uint8_t*>(base_), size_);
  base_ = nullptr;
  size_ = 0;
  pos_ = 0;
  open_ = false;
}

void LcmLogReader::rewind() {
  pos_ = 0;
  stats_ = LcmLogReadStats{};
}

bool LcmLogReader::sync_at(std::uint64_t pos) const {
  return pos + 4 <= size_ && be32(base_ + pos) == kLcmLogSyncWord;
}

std::uint64_t LcmLogReader::find_sync(std::uint64_t from, std::uint64_t limit) const {
  if (limit > size_) limit = size_;
  while (from < limit) {
    const void* hit = std::memchr(base_ + from, 0xED, limit - from);
    if (hit == nullptr) return limit;
    const auto q = static_cast<std::uint64_t>(static_cast<const std::uint8_t*>(hit) - base_);
    if (sync_at(q)) return q;
    from = q + 1;
  }
  return limit;
}

bool LcmLogReader::plausible_event(std::uint64_t pos) const {
  if (!sync_at(pos) || size_ - pos < kLcmLogHeaderBytes) return false;
  const std::uint32_t chan_len = be32(base_ + pos + 20);
  const std::uint32_t data_len = be32(base_ + pos + 24);
  if (chan_len == 0 || chan_len > kLcmMaxChannelLength || data_len > max_data_) return false;
  if (size_ - pos - kLcmLogHeaderBytes < static_cast<std::uint64_t>(chan_len) + data_len) return false;
  for (std::uint32_t i = 0; i < chan_len; ++i)
    if (!channel_byte_ok(base_[pos + kLcmLogHeaderBytes + i])) return false;
  return true;
}

void LcmLogReader::reject(LcmLogRejection why, std::uint64_t offset, std::uint64_t bytes) {
  ++stats_.rejections[static_cast<int>(why)];
  stats_.bytes_skipped += bytes;
  if (stats_.records.size() < LcmLogReadStats::kMaxRecords) stats_.records.push_back({offset, bytes, why});
}

LcmLogStatus LcmLogReader::next(LcmLogEvent& ev) {
  if (!open_) return LcmLogStatus::kNotOpen;
  if (base_ == nullptr) return LcmLogStatus::kEndOfLog;  // empty file
  while (pos_ < size_) {
    const std::uint64_t p = pos_;
    if (!sync_at(p)) {
      const std::uint64_t q = find_sync(p + 1, size_);
      reject(LcmLogRejection::kNoSync, p, q - p);
      pos_ = q;
      continue;
    }
    if (size_ - p < kLcmLogHeaderBytes) {  // no room for a header: nothing after it either
      reject(LcmLogRejection::kTruncatedEvent, p, size_ - p);
      pos_ = size_;
      break;
    }
    const std::uint8_t* h = base_ + p;
    const std::uint32_t chan_len = be32(h + 20);
    const std::uint32_t data_len = be32(h + 24);
    if (chan_len == 0 || chan_len > kLcmMaxChannelLength) {
      const std::uint64_t q = find_sync(p + 1, size_);
      reject(LcmLogRejection::kBadChannelLength, p, q - p);
      pos_ = q;
      continue;
    }
    if (data_len > max_data_) {
      const std::uint64_t q = find_sync(p + 1, size_);
      reject(LcmLogRejection::kBadDataLength, p, q - p);
      pos_ = q;
      continue;
    }
    const std::uint64_t end = p + kLcmLogHeaderBytes + chan_len + data_len;
    if (end > size_) {
      // Either the file ends inside this event (the last one was cut short) or its length is
      // corrupt and runs over the events after it: resume at the next sync word, if any.
      const std::uint64_t q = find_sync(p + 1, size_);
      if (q == size_) {
        reject(LcmLogRejection::kTruncatedEvent, p, size_ - p);
        pos_ = size_;
        break;
      }
      reject(LcmLogRejection::kBadDataLength, p, q - p);
      pos_ = q;
      continue;
    }
    bool name_ok = true;
    for (std::uint32_t i = 0; i < chan_len && name_ok; ++i) name_ok = channel_byte_ok(h[kLcmLogHeaderBytes + i]);
    if (!name_ok) {
      const std::uint64_t q = find_sync(p + 1, size_);
      reject(LcmLogRejection::kBadChannelName, p, q - p);
      pos_ = q;
      continue;
    }
    // Where does the next event start? Normally at `end`, with the next event number (LCM
    // writers number events consecutively). Otherwise this event's data length may be corrupt
    // (too long, swallowing the events after it): if a plausible event starts inside this one,
    // with the next event number when `end` looks like a boundary, or with any number when it
    // does not, this event is rejected and reading resumes there. If nothing starts inside, the
    // event is kept; damaged bytes after it are skipped (and counted) on the next call.
    const std::uint64_t number = be64(h + 4);
    const bool end_is_boundary = end == size_ || sync_at(end);
    const bool consistent = size_ - end >= 12 && sync_at(end) && be64(base_ + end + 4) == number + 1;
    if (!consistent) {
      bool overlaps = false;
      for (std::uint64_t q = find_sync(p + 1, end); q < end; q = find_sync(q + 1, end)) {
        if (!plausible_event(q)) continue;
        if (!end_is_boundary || be64(base_ + q + 4) == number + 1) {
          reject(LcmLogRejection::kBadDataLength, p, q - p);
          pos_ = q;
          overlaps = true;
          break;
        }
      }
      if (overlaps) continue;
    }
    ev.event_number = static_cast<std::int64_t>(number);
    ev.timestamp_us = static_cast<std::int64_t>(be64(h + 12));
    ev.channel = std::string_view(reinterpret_cast<const char*>(h + kLcmLogHeaderBytes), chan_len);
    ev.data = h + kLcmLogHeaderBytes + chan_len;
    ev.data_len = data_len;
    ev.offset = p;
    pos_ = end;
    ++stats_.events;
    return LcmLogStatus::kOk;
  }
  return LcmLogStatus::kEndOfLog;
}

// ---------------------------------------------------------------------------------------------
LcmLogWriter::~LcmLogWriter() { abort(); }  // docs/faults.md: only close() puts a log in place

LcmLogStatus LcmLogWriter::open(const std::string& path) {
  close();
  path_ = path;
  events_ = 0;
  failures_ = 0;
  if (!file_.open(path)) return LcmLogStatus::kOpenFailed;
  return LcmLogStatus::kOk;
}

LcmLogStatus LcmLogWriter::write(const char* channel, const void* data, std::size_t len, std::int64_t timestamp_us) {
  if (!file_.is_open()) return LcmLogStatus::kNotOpen;
  if (channel == nullptr || !lcm_channel_name_ok(channel)) return LcmLogStatus::kBadChannel;
  if (len > 0x7fffffffu || (len > 0 && data == nullptr)) return LcmLogStatus::kTooLarge;
  const std::size_t chan_len = std::strlen(channel);
  std::uint8_t header[kLcmLogHeaderBytes];
  put32(header, kLcmLogSyncWord);
  put64(header + 4, events_);
  put64(header + 12, static_cast<std::uint64_t>(timestamp_us));
  put32(header + 20, static_cast<std::uint32_t>(chan_len));
  put32(header + 24, static_cast<std::uint32_t>(len));
  if (!file_.write(header, sizeof(header)) || !file_.write(channel, chan_len) || (len > 0 && !file_.write(data, len))) {
    ++failures_;
    return LcmLogStatus::kWriteFailed;
  }
  ++events_;
  return LcmLogStatus::kOk;
}

LcmLogStatus LcmLogWriter::flush() {
  if (!file_.is_open()) return LcmLogStatus::kNotOpen;
  if (!file_.flush()) {
    ++failures_;
    return LcmLogStatus::kWriteFailed;
  }
  return LcmLogStatus::kOk;
}

LcmLogStatus LcmLogWriter::close() {
  if (!file_.is_open()) return LcmLogStatus::kOk;
  if (!file_.commit()) {
    ++failures_;
    return LcmLogStatus::kWriteFailed;
  }
  return LcmLogStatus::kOk;
}

void LcmLogWriter::abort() { file_.abort(); }

}  // namespace hal
