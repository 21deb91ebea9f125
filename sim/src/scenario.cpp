// Scenario TOML parser: every key optional (struct defaults otherwise), unknown keys rejected, each
// error reported as "<source>:<line>:<col>: <message naming the dotted key path>". The schema is
// documented in sim/scenarios/README.md.
#include "sim/scenario.hpp"

#include "cfg/data_dir.hpp"
#include "cfg/text_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>

#include "cfg/toml_schema.hpp"

#include "fsw/gnss.hpp"

namespace sim {

std::vector<Segment> Scenario::default_segments() {
  const Segment right{.type = SegmentType::kTurn, .direction = TurnDirection::kRight, .bank_deg = 60.0,
                      .heading_change_deg = 180.0, .roll_time_s = 5.0};
  Segment left = right;
  left.direction = TurnDirection::kLeft;
  return {Segment{.type = SegmentType::kStraight, .duration_s = 60.0}, right,
          Segment{.type = SegmentType::kStraight, .duration_s = 30.0}, left,
          Segment{.type = SegmentType::kStraight, .duration_s = 30.0}};
}

const char* to_string(SegmentType t) {
  switch (t) {
    case SegmentType::kStraight: return "straight";
    case SegmentType::kTurn: return "turn";
    case SegmentType::kSpeedChange: return "speed_change";
    case SegmentType::kClimb: return "climb";
    case SegmentType::kRoll: return "roll";
    case SegmentType::kCrab: return "crab";
  }
  return "?";
}

std::string default_almanac_path() { return cfg::data_file("almanac/yuma-week431.alm"); }

std::string almanac_path(const GpsConfig& cfg) { return cfg.almanac.empty() ? default_almanac_path() : cfg.almanac; }

namespace {

using cfg::toml_schema::closed;
using cfg::toml_schema::got;
using cfg::toml_schema::left_open;
using cfg::toml_schema::non_negative;
using cfg::toml_schema::positive;
using cfg::toml_schema::Range;
using cfg::toml_schema::right_open;

class Parser : public cfg::toml_schema::Reader {
 public:
  using Reader::Reader;

  bool scenario(const toml::table& root, Scenario& s) {
    return fields(root, "", {
        {"name", text(s.name)},
        {"duration_s", number(s.duration_s, left_open(0.0, 86400.0))},
        {"seed", [&](const toml::node& n, const std::string& p) {
           const auto* v = n.as_integer();
           if (!v || v->get() < 0) return fail(n, "'" + p + "' must be an integer >= 0" + got(n));
           s.seed = static_cast<std::uint64_t>(v->get());
           return true;
         }},
        {"start", [&](const toml::node& n, const std::string& p) { return start(n, p, s.start); }},
        {"trajectory", [&](const toml::node& n, const std::string& p) { return trajectory(n, p, s); }},
        {"imu", [&](const toml::node& n, const std::string& p) { return imu(n, p, s.imu); }},
        {"effects", [&](const toml::node& n, const std::string& p) { return effects(n, p, s.effects); }},
        {"gps", [&](const toml::node& n, const std::string& p) { return gps(n, p, s.gps); }},
    });
  }


 private:
  bool start(const toml::node& n, const std::string& path, StartState& s) {
    const toml::table* t = table(n, path);
    return t && fields(*t, path + ".", {
        {"lat_deg", number(s.lat_deg, closed(-85.0, 85.0))},
        {"lon_deg", number(s.lon_deg, right_open(-180.0, 360.0))},
        {"alt_m", number(s.alt_m, closed(-400.0, 30000.0))},
        {"speed_mps", number(s.speed_mps, left_open(0.0, 1000.0))},
        {"heading_deg", number(s.heading_deg, closed(-360.0, 360.0))},
        {"pitch_deg", number(s.pitch_deg, closed(-30.0, 30.0))},
    });
  }

  /// The segment list is read before repeat_from, which is checked against its length.
  bool trajectory(const toml::node& n, const std::string& path, Scenario& s) {
    const toml::table* t = table(n, path);
    const Handler later = [](const toml::node&, const std::string&) { return true; };
    if (!t || !fields(*t, path + ".", {{"repeat_from", later}, {"segment", later}})) return false;
    if (const toml::node* list = t->get("segment")) {
      if (!segments(*list, path + ".segment", s.segments)) return false;
      s.repeat_from = std::nullopt;
    }
    const toml::node* repeat = t->get("repeat_from");
    if (!repeat) return true;
    if (const auto* none = repeat->as_string(); none && none->get() == "none") {
      s.repeat_from = std::nullopt;
      return true;
    }
    const auto* index = repeat->as_integer();
    if (!index || index->get() < 0 || static_cast<std::size_t>(index->get()) >= s.segments.size()) {
      return fail(*repeat, "'" + path + ".repeat_from' must be \"none\" or a segment index in [0, " +
                               std::to_string(s.segments.size() - 1) + "]" + got(*repeat));
    }
    s.repeat_from = static_cast<std::size_t>(index->get());
    return true;
  }

  bool segments(const toml::node& n, const std::string& path, std::vector<Segment>& out) {
    const toml::array* list = n.as_array();
    if (list && list->empty()) return fail(n, "'" + path + "' must not be empty");
    if (!list || !list->is_array_of_tables()) {
      return fail(n, "'" + path + "' must be an array of tables ([[" + path + "]] entries)" + (list ? "" : got(n)));
    }
    out.assign(list->size(), Segment{});
    for (std::size_t i = 0; i < list->size(); ++i) {
      if (!segment(*list->get(i)->as_table(), path + "[" + std::to_string(i) + "]", out[i])) return false;
    }
    return true;
  }

  bool segment(const toml::table& t, const std::string& path, Segment& seg) {
    const toml::node* type = t.get("type");
    if (!type) {
      return fail(t, "'" + path + ".type' is required (\"straight\", \"turn\", \"speed_change\", \"climb\", \"roll\" or \"crab\")");
    }
    if (!choice(seg.type, {{"straight", SegmentType::kStraight},
                           {"turn", SegmentType::kTurn},
                           {"speed_change", SegmentType::kSpeedChange},
                           {"climb", SegmentType::kClimb},
                           {"roll", SegmentType::kRoll},
                           {"crab", SegmentType::kCrab}})(*type, path + ".type")) {
      return false;
    }
    const SegmentType type_of_segment = seg.type;
    using Types = std::initializer_list<SegmentType>;
    const auto only = [this, type_of_segment](Types allowed, Handler h) -> Handler {
      const std::vector<SegmentType> ok(allowed);
      return [this, ok, type_of_segment, h](const toml::node& n, const std::string& p) {
        if (std::find(ok.begin(), ok.end(), type_of_segment) == ok.end()) {
          return fail(n, "'" + p + "' is not allowed for a " + to_string(type_of_segment) + " segment");
        }
        return h(n, p);
      };
    };
    const SegmentType straight = SegmentType::kStraight, turn = SegmentType::kTurn;
    const SegmentType speed = SegmentType::kSpeedChange, climb = SegmentType::kClimb, roll = SegmentType::kRoll;
    const SegmentType crab = SegmentType::kCrab;
    // The hold of a climb, roll or crab may be 0 (pull-up then push-over); every other duration is positive.
    const bool zero_ok = seg.type == climb || seg.type == roll || seg.type == crab;
    // A signed amount in [-limit, limit] that must not be 0 (a speed change or climb of nothing).
    const auto nonzero = [this](double& v, double limit) -> Handler {
      return [this, &v, limit](const toml::node& n, const std::string& p) {
        const auto* d = n.as_floating_point();
        const auto* i = n.as_integer();
        const double x = d ? d->get() : i ? static_cast<double>(i->get()) : 0.0;
        if ((!d && !i) || !std::isfinite(x) || x == 0.0 || std::abs(x) > limit) {
          std::ostringstream range;
          range << "[" << -limit << ", " << limit << "]";
          return fail(n, "'" + p + "' must be a number in " + range.str() + ", not 0" + got(n));
        }
        v = x;
        return true;
      };
    };
    return fields(t, path + ".", {
        {"type", [](const toml::node&, const std::string&) { return true; }},
        {"duration_s", only({straight, speed, climb, roll, crab},
                            number(seg.duration_s, zero_ok ? closed(0.0, 86400.0) : left_open(0.0, 86400.0)))},
        {"direction", only({turn, roll, crab}, choice(seg.direction, {{"left", TurnDirection::kLeft}, {"right", TurnDirection::kRight}}))},
        {"bank_deg", only({turn, roll}, number(seg.bank_deg, left_open(0.0, 80.0)))},
        {"heading_change_deg", only({turn}, number(seg.heading_change_deg, left_open(0.0, 3600.0)))},
        {"roll_time_s", only({turn, roll}, number(seg.roll_time_s, left_open(0.0, 60.0)))},
        {"delta_speed_mps", only({speed}, nonzero(seg.delta_speed_mps, 400.0))},
        {"flight_path_deg", only({climb}, nonzero(seg.flight_path_deg, 45.0))},
        {"transition_s", only({climb, crab}, number(seg.transition_s, left_open(0.0, 120.0)))},
        {"crab_deg", only({crab}, number(seg.crab_deg, left_open(0.0, 45.0)))},
    });
  }

  bool imu(const toml::node& n, const std::string& path, ImuConfig& cfg) {
    const toml::table* t = table(n, path);
    ImuErrorSigmas& s = cfg.sigmas;
    return t && fields(*t, path + ".", {
        {"rate_hz", [&](const toml::node& node, const std::string& p) {
           const auto* v = node.as_integer();
           if (!v || v->get() < 200 || v->get() > 6400 || v->get() % 200 != 0) {
             return fail(node, "'" + p + "' must be an integer multiple of 200 in [200, 6400]" + got(node));
           }
           cfg.rate_hz = static_cast<int>(v->get());
           return true;
         }},
        {"errors", choice(cfg.errors, {{"paper", ImuErrorSet::kPaper}, {"baseline", ImuErrorSet::kBaseline},
                                       {"none", ImuErrorSet::kNone}})},
        {"accel_bias_ug", number(s.accel_bias_ug, non_negative())},
        {"accel_scale_factor_ppm", number(s.accel_scale_factor_ppm, non_negative())},
        {"accel_misalignment_arcsec", number(s.accel_misalignment_arcsec, non_negative())},
        {"gyro_bias_degph", number(s.gyro_bias_degph, non_negative())},
        {"gyro_scale_factor_ppm", number(s.gyro_scale_factor_ppm, non_negative())},
        {"gyro_misalignment_arcsec", number(s.gyro_misalignment_arcsec, non_negative())},
        {"gyro_arw_deg_per_rthr", number(s.gyro_arw_deg_per_rthr, non_negative())},
        {"accel_vrw_ug_per_rthz", number(s.accel_vrw_ug_per_rthz, non_negative())},
        {"gyro_bias_instability_degph", number(s.gyro_bias_instability_degph, non_negative())},
        {"accel_bias_instability_ug", number(s.accel_bias_instability_ug, non_negative())},
        {"bias_instability_tau_s", number(s.bias_instability_tau_s, positive())},
        {"gyro_bias_rw_degph_per_rthr", number(s.gyro_bias_rw_degph_per_rthr, non_negative())},
        {"accel_bias_rw_ug_per_rthr", number(s.accel_bias_rw_ug_per_rthr, non_negative())},
        {"mounting_rpy_deg", mounting(cfg.mounting_rpy_deg)},
    });
  }

  /// [roll, pitch, yaw] in degrees: roll and yaw in [-180, 180], pitch in [-90, 90].
  Handler mounting(std::array<double, 3>& out) {
    return [this, &out](const toml::node& n, const std::string& p) {
      const auto* a = n.as_array();
      if (!a || a->size() != 3)
        return fail(n, "'" + p + "' must be an array of 3 numbers [roll, pitch, yaw] in degrees" + got(n));
      std::array<double, 3> v{};
      const Range ranges[3] = {closed(-180.0, 180.0), closed(-90.0, 90.0), closed(-180.0, 180.0)};
      for (std::size_t i = 0; i < 3; ++i)
        if (!read_number(*a->get(i), p + "[" + std::to_string(i) + "]", ranges[i], v[i])) return false;
      out = v;
      return true;
    };
  }

  bool gps(const toml::node& n, const std::string& path, GpsConfig& g) {
    const toml::table* t = table(n, path);
    return t && fields(*t, path + ".", {
        {"almanac", [&](const toml::node& node, const std::string& p) {
           const auto* v = node.as_string();
           if (!v) return fail(node, "'" + p + "' must be a string (a file path, \"\" for the default)" + got(node));
           g.almanac = v->get();
           return true;
         }},
        {"start_week", integer(g.start_week, 0, 9999)},
        {"start_tow_s", number(g.start_tow_s, right_open(0.0, 604800.0))},
        {"rate_hz", number(g.rate_hz, left_open(0.0, 20.0))},
        {"elevation_mask_deg", number(g.elevation_mask_deg, right_open(0.0, 90.0))},
        {"pseudorange_gm_sigma_m", number(g.pseudorange_gm_sigma_m, non_negative())},
        {"pseudorange_gm_tau_s", number(g.pseudorange_gm_tau_s, positive())},
        {"pseudorange_rate_gm_sigma_mps", number(g.pseudorange_rate_gm_sigma_mps, non_negative())},
        {"pseudorange_rate_gm_tau_s", number(g.pseudorange_rate_gm_tau_s, positive())},
        {"pseudorange_white_sigma_m", number(g.pseudorange_white_sigma_m, non_negative())},
        {"pseudorange_rate_white_sigma_mps", number(g.pseudorange_rate_white_sigma_mps, non_negative())},
        {"clock_bias_sigma_m", number(g.clock_bias_sigma_m, non_negative())},
        {"clock_drift_sigma_mps", number(g.clock_drift_sigma_mps, non_negative())},
        {"clock_h0_s", number(g.clock_h0_s, non_negative())},
        {"clock_h_minus2_per_s", number(g.clock_h_minus2_per_s, non_negative())},
        {"clock_h0", renamed("clock_h0_s")},
        {"clock_h_minus2", renamed("clock_h_minus2_per_s")},
        {"max_channels", integer(g.max_channels, 1, fsw::kMaxGnssChannels)},
    });
  }

  /// Scalar effects take a number, multi-component effects a table of components (catalogue units).
  bool effects(const toml::node& n, const std::string& path, EffectSet& set) {
    const toml::table* t = table(n, path);
    if (!t) return false;
    for (auto&& [key, value] : *t) {
      const std::string name(key.str());
      const std::string effect_path = path + "." + name;
      const std::optional<Effect> e = effect_from_name(name);
      if (!e) return fail(key, "unknown effect '" + effect_path + "' (valid: " + effect_names() + ")");
      if (fsw::effect_info(*e).n_components == 1) {
        double v = 0.0;
        if (!read_number(value, effect_path, Range{}, v)) return false;
        set.set(*e, 0, v);
        continue;
      }
      const toml::table* components = value.as_table();
      if (!components) {
        return fail(value, "'" + effect_path + "' must be a table of components { " + component_names(*e) + " }" +
                               got(value));
      }
      for (auto&& [component_key, component_value] : *components) {
        const std::string component(component_key.str());
        const std::string component_path = effect_path + "." + component;
        const std::optional<std::size_t> k = component_from_name(*e, component);
        if (!k) {
          return fail(component_key, "unknown component '" + component_path + "' (valid: " + component_names(*e) + ")");
        }
        double v = 0.0;
        if (!read_number(component_value, component_path, Range{}, v)) return false;
        set.set(*e, *k, v);
      }
    }
    return true;
  }

};

}  // namespace

ScenarioParseResult parse_scenario_text(const std::string& toml_text, const std::string& source_name) {
  toml::table root;
  std::string error;
  if (!cfg::toml_schema::parse_document(toml_text, source_name, root, error)) return {std::nullopt, error};
  Scenario scenario;
  Parser parser(source_name);
  if (!parser.scenario(root, scenario)) return {std::nullopt, parser.error()};
  return {std::move(scenario), ""};
}

ScenarioParseResult parse_scenario_file(const std::string& path) {
  const std::optional<std::string> text = cfg::read_text_file(path);
  if (!text) return {std::nullopt, path + ": cannot open scenario file: " + cfg::text_file_problem(path)};
  ScenarioParseResult r = parse_scenario_text(*text, path);
  if (r.scenario && !r.scenario->gps.almanac.empty()) {
    try {
      const std::filesystem::path almanac(r.scenario->gps.almanac);
      if (almanac.is_relative()) {
        const std::filesystem::path dir = std::filesystem::absolute(std::filesystem::path(path)).parent_path();
        r.scenario->gps.almanac = (dir / almanac).lexically_normal().string();
      }
    } catch (const std::exception& e) {  // std::filesystem::absolute may throw filesystem_error
      return {std::nullopt, path + ": cannot resolve 'gps.almanac': " + e.what()};
    }
  }
  return r;
}

}  // namespace sim
