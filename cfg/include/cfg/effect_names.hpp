// The effect catalogue's names as the files spell them (fsw/effect_catalogue.hpp): shared by the
// flight configuration's [diagnosis.prior] table and the scenario files' [effects] (sim/).
#pragma once

#include <optional>
#include <string>

#include "fsw/effect_catalogue.hpp"

namespace cfg {

/// Looks up an effect by catalogue name ("gyro_misalignment"); nullopt when unknown.
std::optional<fsw::Effect> effect_from_name(const std::string& name);
/// The catalogue names, comma-separated (for error messages).
std::string effect_names();

}  // namespace cfg
