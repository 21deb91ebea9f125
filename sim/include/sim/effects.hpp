// Values of the truth-side effects of the catalogue (fsw/effect_catalogue.hpp), in catalogue units.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "cfg/effect_names.hpp"
#include "fsw/effect_catalogue.hpp"

namespace sim {

using fsw::Effect;

/// A set of switched-on effects. Each effect has up to 6 component values in catalogue units
/// (arcsec, ppm, deg/h/g, s, m or scale); an effect is on when any of its components is non-zero.
struct EffectSet {
  std::array<std::array<double, fsw::kMaxEffectComponents>, fsw::kEffectCount> value{};

  double get(Effect e, std::size_t component = 0) const { return value[static_cast<std::size_t>(e)][component]; }
  void set(Effect e, std::size_t component, double v) { value[static_cast<std::size_t>(e)][component] = v; }
  bool on(Effect e) const {
    for (double v : value[static_cast<std::size_t>(e)]) {
      if (v != 0.0) return true;
    }
    return false;
  }
  /// The value of component k in SI units (rad, unitless, rad/s per m/s^2, s, m).
  double si(Effect e, std::size_t component = 0) const { return get(e, component) * fsw::effect_info(e).unit_to_si; }
  bool operator==(const EffectSet&) const = default;
};

/// The catalogue's names (cfg/effect_names.hpp: the files' spelling, shared with the flight configuration).
using cfg::effect_from_name;
using cfg::effect_names;
/// Looks up a component index by name ("xy"; "" for scalar effects); nullopt when unknown.
std::optional<std::size_t> component_from_name(Effect e, const std::string& component);
/// The component names of effect e, comma-separated (for error messages).
std::string component_names(Effect e);
/// Parses "NAME[.COMPONENT]=VALUE" (the --effect syntax) into the set; returns an error message or "".
std::string apply_effect_assignment(EffectSet& set, const std::string& assignment);

}  // namespace sim
