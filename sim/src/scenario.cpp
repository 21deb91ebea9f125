// Scenario TOML parser: every key optional (struct defaults otherwise), unknown keys rejected, each
// error reported as "<source>:<line>:<col>: <message naming the dotted key path>". The schema is
// documented in sim/scenarios/README.md.
#include "sim/scenario.hpp"
#include "sim/text_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <string_view>
#include <utility>

#include <toml++/toml.h>

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

std::string default_almanac_path() { return std::string(SDINS_SHARED_DATA_DIR) + "/almanac/yuma-week431.alm"; }

std::string almanac_path(const GpsConfig& cfg) { return cfg.almanac.empty() ? default_almanac_path() : cfg.almanac; }

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// TOML 1.0 allows non-ASCII text only inside strings and comments. Position ("line:col") of the
/// first non-ASCII byte anywhere else, or empty. Checked before toml::parse because toml++ 3.3.0
/// (Debian 12) runs into __builtin_unreachable() (undefined behaviour) when it meets some non-ASCII
/// code points in syntax positions (its is_non_ascii_horizontal_whitespace() for U+00A1..U+0499,
/// U+2C6E..U+3067 and U+FB26..U+FEFE); found by fuzz/fuzz_scenario.cpp, regression input in
/// fuzz/regressions/scenario/.
std::string non_ascii_outside_strings(const std::string& text) {
  enum class State { kCode, kComment, kBasic, kLiteral, kMultiBasic, kMultiLiteral };
  State st = State::kCode;
  int line = 1, col = 0;
  const auto starts = [&text](std::size_t i, const char* s) { return text.compare(i, std::strlen(s), s) == 0; };
  const std::size_t bom = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;  // a leading UTF-8 BOM is allowed
  for (std::size_t i = bom; i < text.size(); ++i) {
    const char c = text[i];
    ++col;
    if (c == '\n') {
      ++line;
      col = 0;
      if (st == State::kComment || st == State::kBasic || st == State::kLiteral) st = State::kCode;
      continue;
    }
    std::size_t skip = 0;  // further bytes consumed by this step
    switch (st) {
      case State::kCode:
        if (static_cast<unsigned char>(c) >= 0x80) return std::to_string(line) + ":" + std::to_string(col);
        if (c == '#') {
          st = State::kComment;
        } else if (starts(i, "\"\"\"")) {
          st = State::kMultiBasic;
          skip = 2;
        } else if (starts(i, "'''")) {
          st = State::kMultiLiteral;
          skip = 2;
        } else if (c == '"') {
          st = State::kBasic;
        } else if (c == '\'') {
          st = State::kLiteral;
        }
        break;
      case State::kComment:
        break;
      case State::kBasic:
      case State::kMultiBasic:
        if (c == '\\' && i + 1 < text.size() && text[i + 1] != '\n') {
          skip = 1;  // an escaped character (\" included) never ends the string
        } else if (st == State::kBasic && c == '"') {
          st = State::kCode;
        } else if (st == State::kMultiBasic && starts(i, "\"\"\"")) {
          st = State::kCode;
          skip = 2;  // and up to two more quotes, which belong to the content (""""" ends "" + """)
          while (skip < 4 && i + skip + 1 < text.size() && text[i + skip + 1] == '"') ++skip;
        }
        break;
      case State::kLiteral:
        if (c == '\'') st = State::kCode;
        break;
      case State::kMultiLiteral:
        if (starts(i, "'''")) {
          st = State::kCode;
          skip = 2;
          while (skip < 4 && i + skip + 1 < text.size() && text[i + skip + 1] == '\'') ++skip;
        }
        break;
    }
    i += skip;
    col += static_cast<int>(skip);
  }
  return "";
}

std::string format_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

/// A validity interval; infinite bounds mean "unbounded" (values must be finite regardless).
struct Range {
  double lo = -kInf;
  double hi = kInf;
  bool lo_open = false;
  bool hi_open = false;

  bool contains(double v) const {
    return std::isfinite(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  std::string text() const {
    if (std::isinf(lo) && std::isinf(hi)) return "a finite number";
    if (std::isinf(hi)) return std::string("a finite number ") + (lo_open ? "> " : ">= ") + format_number(lo);
    return std::string("a number in ") + (lo_open ? "(" : "[") + format_number(lo) + ", " + format_number(hi) +
           (hi_open ? ")" : "]");
  }
};

constexpr Range closed(double lo, double hi) { return {lo, hi, false, false}; }
constexpr Range left_open(double lo, double hi) { return {lo, hi, true, false}; }
constexpr Range right_open(double lo, double hi) { return {lo, hi, false, true}; }
constexpr Range non_negative() { return {0.0, kInf, false, false}; }
constexpr Range positive() { return {0.0, kInf, true, false}; }

/// " (got <value>)" for error messages.
std::string got(const toml::node& n) {
  std::string what;
  if (const auto* s = n.as_string()) {
    what = "\"" + s->get() + "\"";
  } else if (const auto* i = n.as_integer()) {
    what = std::to_string(i->get());
  } else if (const auto* f = n.as_floating_point()) {
    what = format_number(f->get());
  } else if (const auto* b = n.as_boolean()) {
    what = b->get() ? "true" : "false";
  } else {
    std::ostringstream os;
    os << n.type();
    what = (n.is_array() ? "an " : "a ") + os.str();
  }
  return " (got " + what + ")";
}

class Parser {
 public:
  using Handler = std::function<bool(const toml::node&, const std::string& path)>;
  struct Field {
    std::string_view key;
    Handler handle;
  };

  explicit Parser(std::string source) : source_(std::move(source)) {}
  const std::string& error() const { return error_; }

  bool scenario(const toml::table& root, Scenario& s) {
    return fields(root, "", {
        {"name", [&](const toml::node& n, const std::string& p) {
           const auto* v = n.as_string();
           if (!v) return fail(n, "'" + p + "' must be a string" + got(n));
           s.name = v->get();
           return true;
         }},
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
  /// Records the error at the node's (or key's) position; returns false so callers can `return fail(...)`.
  template <typename Located>
  bool fail(const Located& where, const std::string& message) {
    const toml::source_position& pos = where.source().begin;
    error_ = source_ + ":" + std::to_string(pos.line) + ":" + std::to_string(pos.column) + ": " + message;
    return false;
  }

  /// Runs the handler of each key of t; a key without a handler is rejected.
  bool fields(const toml::table& t, const std::string& prefix, std::initializer_list<Field> known) {
    for (auto&& [key, node] : t) {
      const std::string path = prefix + std::string(key.str());
      // Compared through a named copy: clang before 16 cannot capture a structured binding.
      const std::string_view name = key.str();
      const auto field = std::find_if(known.begin(), known.end(), [&](const Field& f) { return f.key == name; });
      if (field == known.end()) return fail(key, "unknown key '" + path + "'");
      if (!field->handle(node, path)) return false;
    }
    return true;
  }

  const toml::table* table(const toml::node& n, const std::string& path) {
    if (const auto* t = n.as_table()) return t;
    fail(n, "'" + path + "' must be a table" + got(n));
    return nullptr;
  }

  bool read_number(const toml::node& n, const std::string& path, Range range, double& out) {
    const std::optional<double> v = n.is_number() ? n.value<double>() : std::nullopt;
    if (!v || !range.contains(*v)) return fail(n, "'" + path + "' must be " + range.text() + got(n));
    out = *v;
    return true;
  }

  Handler number(double& out, Range range) {
    return [this, &out, range](const toml::node& n, const std::string& p) { return read_number(n, p, range, out); };
  }

  /// An integer key (a float such as 12.0 is rejected) in [lo, hi].
  Handler integer(int& out, int lo, int hi) {
    return [this, &out, lo, hi](const toml::node& n, const std::string& p) {
      const auto* v = n.as_integer();
      if (!v || v->get() < lo || v->get() > hi) {
        return fail(n, "'" + p + "' must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]" +
                           got(n));
      }
      out = static_cast<int>(v->get());
      return true;
    };
  }

  template <typename E>
  Handler choice(E& out, std::vector<std::pair<std::string_view, E>> options) {
    return [this, &out, options](const toml::node& n, const std::string& p) {
      std::string expected;
      for (std::size_t i = 0; i < options.size(); ++i) {
        const auto& [name, value] = options[i];
        if (const auto* s = n.as_string(); s && s->get() == name) {
          out = value;
          return true;
        }
        expected += (i == 0 ? "" : i + 1 == options.size() ? " or " : ", ") + ("\"" + std::string(name) + "\"");
      }
      return fail(n, "'" + p + "' must be " + expected + got(n));
    };
  }

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
    if (!type) return fail(t, "'" + path + ".type' is required (\"straight\" or \"turn\")");
    if (!choice(seg.type, {{"straight", SegmentType::kStraight}, {"turn", SegmentType::kTurn}})(*type, path + ".type")) {
      return false;
    }
    const SegmentType type_of_segment = seg.type;
    const auto only = [this, type_of_segment](SegmentType allowed, Handler h) -> Handler {
      return [this, allowed, type_of_segment, h](const toml::node& n, const std::string& p) {
        if (type_of_segment != allowed) {
          return fail(n, "'" + p + "' is not allowed for a " +
                             (type_of_segment == SegmentType::kTurn ? "turn" : "straight") + " segment");
        }
        return h(n, p);
      };
    };
    const SegmentType straight = SegmentType::kStraight;
    const SegmentType turn = SegmentType::kTurn;
    return fields(t, path + ".", {
        {"type", [](const toml::node&, const std::string&) { return true; }},
        {"duration_s", only(straight, number(seg.duration_s, left_open(0.0, 86400.0)))},
        {"direction", only(turn, choice(seg.direction, {{"left", TurnDirection::kLeft}, {"right", TurnDirection::kRight}}))},
        {"bank_deg", only(turn, number(seg.bank_deg, left_open(0.0, 80.0)))},
        {"heading_change_deg", only(turn, number(seg.heading_change_deg, left_open(0.0, 3600.0)))},
        {"roll_time_s", only(turn, number(seg.roll_time_s, left_open(0.0, 60.0)))},
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
    });
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
        {"clock_h0", number(g.clock_h0, non_negative())},
        {"clock_h_minus2", number(g.clock_h_minus2, non_negative())},
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

  std::string source_;
  std::string error_;
};

}  // namespace

ScenarioParseResult parse_scenario_text(const std::string& toml_text, const std::string& source_name) {
  if (const std::string at = non_ascii_outside_strings(toml_text); !at.empty())
    return {std::nullopt, source_name + ":" + at +
                              ": non-ASCII character outside a string or comment (TOML allows it only there)"};
  toml::table root;
  try {
    root = toml::parse(std::string_view(toml_text), std::string_view(source_name));
  } catch (const toml::parse_error& e) {
    const toml::source_position& pos = e.source().begin;
    return {std::nullopt, source_name + ":" + std::to_string(pos.line) + ":" + std::to_string(pos.column) + ": " +
                              std::string(e.description())};
  }
  Scenario scenario;
  Parser parser(source_name);
  if (!parser.scenario(root, scenario)) return {std::nullopt, parser.error()};
  return {std::move(scenario), ""};
}

ScenarioParseResult parse_scenario_file(const std::string& path) {
  const std::optional<std::string> text = read_text_file(path);
  if (!text) return {std::nullopt, path + ": cannot open scenario file"};
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
