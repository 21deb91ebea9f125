#include "sim/effects.hpp"

#include <charconv>
#include <cmath>
#include <string_view>

namespace sim {

namespace {

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

}  // namespace

std::optional<std::size_t> component_from_name(Effect e, const std::string& component) {
  const fsw::EffectInfo& info = fsw::effect_info(e);
  for (std::size_t k = 0; k < info.n_components; ++k) {
    if (component == info.components[k]) return k;
  }
  return std::nullopt;
}

std::string component_names(Effect e) {
  const fsw::EffectInfo& info = fsw::effect_info(e);
  std::string names;
  for (std::size_t k = 0; k < info.n_components; ++k) names += (k == 0 ? "" : ", ") + std::string(info.components[k]);
  return names;
}

std::string apply_effect_assignment(EffectSet& set, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos) {
    return "effect assignment '" + assignment + "' is not of the form NAME[.COMPONENT]=VALUE";
  }
  const std::string_view lhs = trim(std::string_view(assignment).substr(0, eq));
  const std::string_view rhs = trim(std::string_view(assignment).substr(eq + 1));
  const auto dot = lhs.find('.');
  const std::string name(lhs.substr(0, dot));
  const bool has_component = dot != std::string_view::npos;
  const std::string component(has_component ? lhs.substr(dot + 1) : std::string_view{});

  const std::optional<Effect> e = effect_from_name(name);
  if (!e) return "unknown effect '" + name + "' (valid: " + effect_names() + ")";
  const bool scalar = fsw::effect_info(*e).n_components == 1;
  if (scalar && has_component) {
    return "effect '" + name + "' is scalar and takes no component (got '" + component + "')";
  }
  if (!scalar && !has_component) {
    return "effect '" + name + "' needs a component: " + name + ".COMPONENT=VALUE with COMPONENT one of " +
           component_names(*e);
  }
  const std::optional<std::size_t> k = component_from_name(*e, component);
  if (!k) return "unknown component '" + component + "' of effect '" + name + "' (valid: " + component_names(*e) + ")";

  const std::string_view number = rhs.starts_with('+') && !rhs.starts_with("+-") ? rhs.substr(1) : rhs;
  double value = 0.0;
  const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), value);
  if (number.empty() || ec != std::errc{} || end != number.data() + number.size() || !std::isfinite(value)) {
    return "bad number '" + std::string(rhs) + "' in effect assignment '" + assignment + "' (expected a finite value in " +
           fsw::effect_info(*e).unit + ")";
  }
  set.set(*e, *k, value);
  return "";
}

}  // namespace sim
