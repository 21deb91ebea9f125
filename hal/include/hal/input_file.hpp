// Bounded input files (docs/faults.md, "bounded readers"): every reader of the CLI opens its file
// through check_input_file() first, so an endless or unbounded input (/dev/zero, /dev/urandom, a
// FIFO, a terminal, a directory) is refused with a message instead of growing memory or spinning
// for ever. A regular file larger than the reader's stated limit is refused as well.
#pragma once

#include <cstdint>
#include <string>

namespace hal {

/// Limits of the readers (bytes). Text inputs (scenario, almanac, filter configuration, profile)
/// are small; recordings (CSV, RINEX, candump) can be long.
inline constexpr std::uint64_t kMaxTextInputBytes = 64ull << 20;       // 64 MiB
inline constexpr std::uint64_t kMaxRecordingInputBytes = 16ull << 30;  // 16 GiB
/// Longest line a line-oriented reader keeps (candump, CSV); longer lines are rejected and counted.
inline constexpr std::size_t kMaxInputLineBytes = 64u << 10;

/// Empty when `path` (links followed) is a regular file of at most max_bytes; otherwise the
/// reason, naming the file ("X: not a regular file (character device)", "X: 2 GiB, above ...").
std::string check_input_file(const std::string& path, std::uint64_t max_bytes);

}  // namespace hal
