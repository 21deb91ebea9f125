// candump log reader and writer (see hal/can_log.hpp).
#include "hal/can_log.hpp"

#include "hal/input_file.hpp"

#include <cerrno>
#include <charconv>
#include <cstring>

namespace hal {
namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}
bool is_space(char c) { return c == ' ' || c == '\t'; }

std::string_view next_token(std::string_view& s) {
  std::size_t i = 0;
  while (i < s.size() && is_space(s[i])) ++i;
  std::size_t j = i;
  while (j < s.size() && !is_space(s[j])) ++j;
  std::string_view tok = s.substr(i, j - i);
  s.remove_prefix(j);
  return tok;
}

}  // namespace

const char* to_string(CandumpLine k) {
  switch (k) {
    case CandumpLine::kFrame: return "frame";
    case CandumpLine::kBlank: return "blank";
    case CandumpLine::kBadTimestamp: return "bad timestamp (expected \"(seconds.fraction)\")";
    case CandumpLine::kNoInterface: return "no interface name";
    case CandumpLine::kNoFrame: return "no ID#DATA field";
    case CandumpLine::kBadId: return "bad identifier (3 or 8 hex digits, 11/29 bits)";
    case CandumpLine::kBadData: return "bad payload (pairs of hex digits)";
    case CandumpLine::kBadLength: return "bad payload length (classic <= 8, FD 0..8,12,16,20,24,32,48,64)";
    case CandumpLine::kBadFdFlags: return "bad CAN FD flags nibble after '##'";
    case CandumpLine::kRemoteFrame: return "remote frame (unsupported)";
    case CandumpLine::kErrorFrame: return "error frame (unsupported)";
    case CandumpLine::kTrailing: return "unexpected text after the frame";
    case CandumpLine::kTooLong: return "line longer than 64 KiB";
  }
  return "unknown";
}

CandumpLine parse_candump_line(std::string_view line, CanFrame& frame, std::string& iface) {
  while (!line.empty() && (line.back() == '\r' || line.back() == '\n' || is_space(line.back()))) line.remove_suffix(1);
  while (!line.empty() && is_space(line.front())) line.remove_prefix(1);
  if (line.empty() || line.front() == '#') return CandumpLine::kBlank;

  // (seconds.fraction)
  if (line.front() != '(') return CandumpLine::kBadTimestamp;
  const std::size_t close = line.find(')');
  if (close == std::string_view::npos || close < 2) return CandumpLine::kBadTimestamp;
  const std::string_view ts = line.substr(1, close - 1);
  int dots = 0;
  for (char c : ts) {
    if (c == '.') ++dots;
    else if (c < '0' || c > '9') return CandumpLine::kBadTimestamp;
  }
  if (dots > 1 || ts.front() == '.' || ts.back() == '.') return CandumpLine::kBadTimestamp;
  double t = 0.0;
  const auto conv = std::from_chars(ts.data(), ts.data() + ts.size(), t);
  if (conv.ec != std::errc() || conv.ptr != ts.data() + ts.size()) return CandumpLine::kBadTimestamp;
  std::string_view rest = line.substr(close + 1);
  if (rest.empty() || !is_space(rest.front())) return rest.empty() ? CandumpLine::kNoInterface : CandumpLine::kBadTimestamp;

  const std::string_view ifname = next_token(rest);
  if (ifname.empty()) return CandumpLine::kNoInterface;
  const std::string_view tok = next_token(rest);
  if (tok.empty()) return CandumpLine::kNoFrame;
  const std::string_view dir = next_token(rest);
  if (!dir.empty() && !(dir == "R" || dir == "T" || dir == "r" || dir == "t")) return CandumpLine::kTrailing;
  if (!next_token(rest).empty()) return CandumpLine::kTrailing;

  const std::size_t hash = tok.find('#');
  if (hash == std::string_view::npos) return CandumpLine::kNoFrame;
  const std::string_view id_s = tok.substr(0, hash);
  if (id_s.size() != 3 && id_s.size() != 8) return CandumpLine::kBadId;
  std::uint32_t id = 0;
  for (char c : id_s) {
    const int v = hex_value(c);
    if (v < 0) return CandumpLine::kBadId;
    id = (id << 4) | static_cast<std::uint32_t>(v);
  }
  const bool extended = id_s.size() == 8;
  if (extended && (id & 0x20000000u)) return CandumpLine::kErrorFrame;
  if (id > (extended ? kCanExtIdMask : kCanStdIdMask)) return CandumpLine::kBadId;

  std::string_view data = tok.substr(hash + 1);
  CanFrame f{};
  f.id = id;
  f.extended = extended;
  f.timestamp_s = t;
  if (!data.empty() && data.front() == '#') {
    f.fd = true;
    if (data.size() < 2) return CandumpLine::kBadFdFlags;
    const int flags = hex_value(data[1]);
    if (flags < 0) return CandumpLine::kBadFdFlags;
    f.brs = (flags & 1) != 0;
    f.esi = (flags & 2) != 0;
    data.remove_prefix(2);
  } else if (!data.empty() && (data.front() == 'R' || data.front() == 'r')) {
    return CandumpLine::kRemoteFrame;
  }
  if (data.size() % 2 != 0) return CandumpLine::kBadData;
  const std::size_t n = data.size() / 2;
  if (n > static_cast<std::size_t>(kCanFdMaxLen)) return CandumpLine::kBadLength;
  for (std::size_t i = 0; i < n; ++i) {
    const int hi = hex_value(data[2 * i]), lo = hex_value(data[2 * i + 1]);
    if (hi < 0 || lo < 0) return CandumpLine::kBadData;
    f.data[i] = static_cast<std::uint8_t>((hi << 4) | lo);
  }
  f.len = static_cast<std::uint8_t>(n);
  if (f.fd ? !can_fd_len_valid(f.len) : f.len > kCanMaxLen) return CandumpLine::kBadLength;
  frame = f;
  iface.assign(ifname.data(), ifname.size());
  return CandumpLine::kFrame;
}

std::string format_candump_line(const CanFrame& f, std::string_view iface) {
  static const char* kHex = "0123456789ABCDEF";
  char head[96];
  std::snprintf(head, sizeof head, "(%.6f) %.*s %0*X#", f.timestamp_s, static_cast<int>(iface.size()), iface.data(),
                f.extended ? 8 : 3, f.id);
  std::string s(head);
  if (f.fd) {
    s += '#';
    s += kHex[(f.brs ? 1 : 0) | (f.esi ? 2 : 0)];
  }
  const int n = f.len <= kCanFdMaxLen ? f.len : kCanFdMaxLen;
  for (int i = 0; i < n; ++i) {
    s += kHex[f.data[static_cast<std::size_t>(i)] >> 4];
    s += kHex[f.data[static_cast<std::size_t>(i)] & 0xF];
  }
  return s;
}

// ---- reader ----

CandumpReader::~CandumpReader() { close(); }

bool CandumpReader::open(const std::string& path) {
  close();
  path_ = path;
  lines_ = frames_ = 0;
  counts_.fill(0);
  problems_.clear();
  error_.clear();
  error_ = check_input_file(path, kMaxRecordingInputBytes);
  if (!error_.empty()) return false;
  f_ = std::fopen(path.c_str(), "r");
  if (f_ == nullptr) {
    error_ = path + ": " + std::strerror(errno);
    return false;
  }
  return true;
}

bool CandumpReader::next(CanFrame& frame, std::string& iface) {
  if (f_ == nullptr) return false;
  for (;;) {
    line_.clear();
    int c = 0;
    bool any = false;
    bool too_long = false;
    while ((c = std::fgetc(f_)) != EOF) {
      any = true;
      if (c == '\n') break;
      if (line_.size() < kMaxInputLineBytes)
        line_ += static_cast<char>(c);
      else
        too_long = true;  // the rest of the line is read and dropped: memory stays bounded
    }
    if (!any) {
      if (std::ferror(f_)) error_ = path_ + ": read error";
      return false;
    }
    ++lines_;
    const CandumpLine k = too_long ? CandumpLine::kTooLong : parse_candump_line(line_, frame, iface);
    ++counts_[static_cast<std::size_t>(k)];
    if (k == CandumpLine::kFrame) {
      ++frames_;
      return true;
    }
    if (k == CandumpLine::kBlank) continue;
    if (static_cast<int>(problems_.size()) < kMaxProblems)
      problems_.push_back(path_ + ":" + std::to_string(lines_) + ": " + to_string(k));
  }
}

void CandumpReader::close() {
  if (f_ != nullptr) std::fclose(f_);
  f_ = nullptr;
}

int CandumpReader::bad_lines() const {
  int n = 0;
  for (int k = 2; k < kCandumpLineKinds; ++k) n += counts_[static_cast<std::size_t>(k)];
  return n;
}

// ---- writer ----

CandumpWriter::~CandumpWriter() { abort(); }  // docs/faults.md: only close() puts a log in place

bool CandumpWriter::open(const std::string& path) {
  close();
  frames_ = 0;
  error_.clear();
  if (!f_.open(path)) {
    error_ = f_.error();
    return false;
  }
  return true;
}

bool CandumpWriter::write(const CanFrame& frame, std::string_view iface) {
  if (!f_.is_open()) {
    error_ = "not open";
    return false;
  }
  if (!can_frame_valid(frame)) {
    error_ = "invalid frame (identifier or length)";
    return false;
  }
  // docs/faults.md: a name the reader would not read back (empty, blanks, '#', '(') is refused,
  // instead of a log of which every line is malformed.
  if (iface.empty() || iface.size() > 64 || iface.find_first_of(" \t\r\n#()") != std::string_view::npos) {
    error_ = f_.path() + ": interface name '" + std::string(iface) + "' cannot be written to a candump log (1 to 64 characters, "
             "no blanks, '#' or parentheses)";
    return false;
  }
  line_ = format_candump_line(frame, iface);
  line_ += '\n';
  if (!f_.write(line_)) {
    error_ = f_.error();
    return false;
  }
  ++frames_;
  return true;
}

bool CandumpWriter::close() {
  if (!f_.is_open()) return error_.empty();
  if (!f_.commit()) {
    if (error_.empty() || !f_.error().empty()) error_ = f_.error();
    return false;
  }
  return true;
}

void CandumpWriter::abort() { f_.abort(); }

// ---- CandumpPacer ---------------------------------------------------------------------------------

namespace {
TimeTagGateConfig pacer_gate() {
  TimeTagGateConfig g;  // the replay reader's band (hal::LcmReplayReader): 2 s ahead, 1 s behind
  g.max_forward_s = 2.0;
  g.max_backward_s = 1.0;
  return g;
}
}  // namespace

CandumpPacer::CandumpPacer() : filter_(pacer_gate()) {}

void CandumpPacer::release(CanFrame&& f) {
  if (have_last_) {
    const double step = f.timestamp_s - last_t_s_;
    if (step > 0.0 && step <= filter_.gate().config().max_forward_s) play_s_ += step;
  }
  have_last_ = true;
  last_t_s_ = f.timestamp_s;
  ready_.emplace_back(f, play_s_);
}

void CandumpPacer::push(const CanFrame& frame) {
  filter_.push(
      frame.timestamp_s, frame, [this](CanFrame&& f) { release(std::move(f)); },
      [this](CanFrame&& f, TimeTagRejection) { ready_.emplace_back(f, play_s_); });  // sent, unpaced
}

void CandumpPacer::finish() {
  filter_.finish([this](CanFrame&& f) { release(std::move(f)); },
                 [this](CanFrame&& f, TimeTagRejection) { ready_.emplace_back(f, play_s_); });
}

bool CandumpPacer::pop(CanFrame& frame, double& play_s) {
  if (ready_.empty()) return false;
  frame = ready_.front().first;
  play_s = ready_.front().second;
  ready_.pop_front();
  return true;
}

}  // namespace hal
