// Whole-file text reading shared by the simulator's file readers (scenario, almanac, profile,
// filter configuration). Bounded (docs/faults.md): regular files of at most kMaxTextFileBytes only.
#pragma once

#include <optional>
#include <string>

namespace cfg {

inline constexpr unsigned long long kMaxTextFileBytes = 64ull << 20;  ///< 64 MiB

/// The whole content of a file; nullopt when it cannot be opened, is not a regular file (a
/// directory, a device such as /dev/zero, a FIFO), is larger than kMaxTextFileBytes, or a read
/// fails. Never throws (allocation failure aside). Callers word the error for their file kind,
/// with text_file_problem() saying why.
std::optional<std::string> read_text_file(const std::string& path);

/// Why read_text_file(path) failed, in a few words ("not a regular file ...", "cannot open").
std::string text_file_problem(const std::string& path);

}  // namespace cfg
