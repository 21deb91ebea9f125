// candump log files (can-utils `candump -L`, python-can's .log): one frame per line,
//   (1699999999.123456) can0 123#DEADBEEF          classic CAN, 11-bit ID (3 hex digits)
//   (1699999999.123456) can0 1ABCDEF0#00           classic CAN, 29-bit ID (8 hex digits)
//   (1699999999.123456) can0 123##1DEADBEEF        CAN FD: '##', one flags nibble (1 = BRS,
//                                                  2 = ESI), then the payload
// An optional trailing " R" / " T" (python-can's direction mark) is accepted. The reader never
// throws and never stops at a bad line: each malformed line is counted under its reason,
// described ("FILE:LINE: reason") in problems() (the first kMaxProblems), and skipped. Remote
// and error frames are counted as unsupported (the sdins protocol uses neither).
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <string>
#include <string_view>
#include <vector>

#include "hal/output_file.hpp"

#include "hal/can_frame.hpp"
#include "hal/time_tag_gate.hpp"

namespace hal {

enum class CandumpLine : std::uint8_t {
  kFrame = 0,       ///< a frame was parsed
  kBlank,           ///< empty line or '#' comment: skipped, not an error
  kBadTimestamp,    ///< missing or malformed "(seconds.fraction)"
  kNoInterface,     ///< no interface name after the timestamp
  kNoFrame,         ///< no ID#DATA field
  kBadId,           ///< identifier not 3 or 8 hex digits, or out of range
  kBadData,         ///< odd number of hex digits or a non-hex character
  kBadLength,       ///< more than 8 bytes classic, more than 64 or not an FD length for FD
  kBadFdFlags,      ///< the '##' flags nibble is missing or not hex
  kRemoteFrame,     ///< ID#R...: unsupported
  kErrorFrame,      ///< error-frame flag in the identifier: unsupported
  kTrailing,        ///< unexpected text after the frame
  kTooLong,         ///< a line longer than hal::kMaxInputLineBytes (kept bounded, then dropped)
};
inline constexpr int kCandumpLineKinds = 13;
const char* to_string(CandumpLine k);

/// Parses one line (without the newline). On kFrame fills frame (timestamp_s included) and iface.
CandumpLine parse_candump_line(std::string_view line, CanFrame& frame, std::string& iface);
/// One frame as a candump log line (no newline): uppercase hex, 6 decimals of timestamp.
std::string format_candump_line(const CanFrame& frame, std::string_view iface);

class CandumpReader {
 public:
  static constexpr int kMaxProblems = 100;
  CandumpReader() = default;
  ~CandumpReader();
  CandumpReader(const CandumpReader&) = delete;
  CandumpReader& operator=(const CandumpReader&) = delete;

  /// false (with error()) if the file cannot be opened, is not a regular file or is larger than
  /// hal::kMaxRecordingInputBytes (hal/input_file.hpp).
  bool open(const std::string& path);
  /// The next frame: true, or false at the end of the file (or on a read error: error() set).
  bool next(CanFrame& frame, std::string& iface);
  void close();

  int lines() const { return lines_; }
  int frames() const { return frames_; }
  /// Malformed lines per reason (index: CandumpLine), kFrame and kBlank excluded from bad_lines().
  int count(CandumpLine k) const { return counts_[static_cast<std::size_t>(k)]; }
  int bad_lines() const;
  const std::vector<std::string>& problems() const { return problems_; }
  const std::string& error() const { return error_; }

 private:
  std::FILE* f_ = nullptr;
  std::string path_;
  int lines_ = 0;
  int frames_ = 0;
  std::array<int, kCandumpLineKinds> counts_{};
  std::vector<std::string> problems_;
  std::string error_;
  std::string line_;
};

class CandumpWriter {
 public:
  CandumpWriter() = default;
  ~CandumpWriter();
  CandumpWriter(const CandumpWriter&) = delete;
  CandumpWriter& operator=(const CandumpWriter&) = delete;
  /// false (with error()) if the file cannot be created.
  bool open(const std::string& path);
  /// false (with error()) on a write error or an invalid frame.
  bool write(const CanFrame& frame, std::string_view iface);
  /// Flushes, fsyncs, closes and renames into place (hal::OutputFile); false on a write error.
  bool close();
  /// Drops the output: the target is left as it was.
  void abort();
  int frames() const { return frames_; }
  const std::string& error() const { return error_; }

 private:
  OutputFile f_;
  int frames_ = 0;
  std::string error_;
  std::string line_;
};

/// Log time -> play time for a player that paces frames by their timestamps (`sdins can play
/// --realtime`, docs/faults.md). The timestamps go through the replay reader's time-tag gate
/// (hal::TimeTagGate, 2 s ahead / 1 s behind): only the steps between accepted tags within that band
/// advance the play clock. One wild timestamp (a day ahead) costs no sleep: the frame is still sent,
/// at the play time of the frame before it, and counted (stats().outliers); a sustained jump (a new
/// time base, counted) is a step of 0; a step backwards is no pause. The frames come out in log order.
class CandumpPacer {
 public:
  CandumpPacer();
  /// One frame of the log; then pop() the frames it released (the gate may hold a few).
  void push(const CanFrame& frame);
  /// End of the log: releases what is still held.
  void finish();
  /// The next released frame and its play time [s after the first frame].
  bool pop(CanFrame& frame, double& play_s);
  const TimeTagGateStats& stats() const { return filter_.stats(); }

 private:
  void release(CanFrame&& f);
  TimeTagFilter<CanFrame> filter_;
  std::deque<std::pair<CanFrame, double>> ready_;
  bool have_last_ = false;
  double last_t_s_ = 0.0;
  double play_s_ = 0.0;
};

}  // namespace hal
