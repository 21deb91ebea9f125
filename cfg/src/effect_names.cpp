#include "cfg/effect_names.hpp"

namespace cfg {

std::optional<fsw::Effect> effect_from_name(const std::string& name) {
  for (const fsw::EffectInfo& info : fsw::kEffectCatalogue) {
    if (name == info.name) return info.effect;
  }
  return std::nullopt;
}

std::string effect_names() {
  std::string names;
  for (const fsw::EffectInfo& info : fsw::kEffectCatalogue) names += (names.empty() ? "" : ", ") + std::string(info.name);
  return names;
}

}  // namespace cfg
