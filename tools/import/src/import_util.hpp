// Small text-parsing helpers of the importers (private to tools/import).
#pragma once

#include <cstdint>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

#include "hal/time_tag_gate.hpp"
#include "tools/importers.hpp"

namespace tools::import_util {

std::string_view trim(std::string_view s);
/// Fields separated by sep (empty fields kept).
std::vector<std::string_view> split(std::string_view s, char sep);
/// Whitespace-separated tokens.
std::vector<std::string_view> split_ws(std::string_view s);
/// The whole (trimmed) field as a number; "nan"/"inf" parse (callers check finiteness).
bool parse_double(std::string_view s, double& v);
bool parse_int(std::string_view s, std::int64_t& v);
/// A Fortran number with a D exponent (RINEX): ".344484578818D-03".
bool parse_fortran_double(std::string_view s, double& v);
/// std::getline that also says whether the line ended with '\n' (false for a last line cut off).
bool getline_counted(std::istream& in, std::string& line, bool& terminated);
std::vector<std::uint8_t> read_file_bytes(const std::string& path);

/// The importers' time-tag gate (hal::TimeTagGate, shared with the replay reader): a line whose
/// time jumps alone is rejected ("time-tag outlier") and the file goes on; a jump that
/// confirm_samples lines agree with is a new time base (counted in LineStats). `T` has `line`.
template <class T>
class LineTimeGate {
 public:
  LineTimeGate(LineStats& stats, std::vector<T>& out, const hal::TimeTagGateConfig& cfg)
      : stats_(stats), out_(out), filter_(cfg) {}
  void push(double t, T item) {
    filter_.push(t, std::move(item), [this](T&& a) { accept(std::move(a)); },
                 [this](T&& a, hal::TimeTagRejection r) { stats_.reject(a.line, hal::to_string(r)); });
    const hal::TimeTagGateStats& g = filter_.stats();
    if (g.new_bases > stats_.time_base_changes) {
      stats_.time_base_changes = g.new_bases;
      stats_.last_time_jump = g.last_new_base_jump_s;
      stats_.last_time_jump_line = out_.empty() ? 0 : out_.back().line;
    }
  }
  void finish() {
    filter_.finish([this](T&& a) { accept(std::move(a)); },
                   [this](T&& a, hal::TimeTagRejection r) { stats_.reject(a.line, hal::to_string(r)); });
  }

 private:
  void accept(T&& a) {
    ++stats_.accepted;
    out_.push_back(std::move(a));
  }
  LineStats& stats_;
  std::vector<T>& out_;
  hal::TimeTagFilter<T> filter_;
};

/// The checks every line-oriented reader makes of a data line before parsing it: counts it, and
/// rejects (counted, with its line number) an empty line and a partial last line (no newline).
/// True when the line is to be parsed.
inline bool take_data_line(LineStats& stats, std::uint64_t line_no, std::string_view s, bool terminated) {
  ++stats.lines;
  if (s.empty()) {
    stats.reject(line_no, "empty line");
    return false;
  }
  if (!terminated) {
    stats.reject(line_no, "partial last line (no newline)");
    return false;
  }
  return true;
}

inline hal::TimeTagGateConfig gate_config(double max_forward, double max_backward, bool strict) {
  hal::TimeTagGateConfig g;
  g.max_forward_s = max_forward;
  g.max_backward_s = max_backward;
  g.strictly_increasing = strict;
  g.confirm_samples = kTimeBaseConfirmLines;
  return g;
}


}  // namespace tools::import_util
