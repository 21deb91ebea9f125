// Whole-file text reading shared by the simulator's file readers (scenario, almanac, profile).
#pragma once

#include <optional>
#include <string>

namespace sim {

/// The whole content of a file; nullopt when it cannot be opened, is a directory, or a read
/// fails. Never throws (allocation failure aside). Callers word the error for their file kind.
std::optional<std::string> read_text_file(const std::string& path);

}  // namespace sim
