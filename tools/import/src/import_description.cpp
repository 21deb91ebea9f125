// The recording description's TOML schema (tools/import_describe.hpp, docs/own-recording.md): the
// same reader rules and error format as the scenario and filter-configuration files
// (sim/src/toml_schema.hpp): every key optional unless said, unknown keys rejected, each error
// "<file>:<line>:<col>: <message naming the dotted key>".
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fsw/frames.hpp"
#include "hal/input_file.hpp"
#include "cfg/toml_schema.hpp"
#include "tools/import_describe.hpp"

namespace tools {
namespace {

namespace ts = cfg::toml_schema;
using ts::got;

/// Units a column may carry, by quantity: name -> SI per unit.
struct UnitTable {
  const char* what;
  std::vector<std::pair<std::string_view, double>> units;
};
const UnitTable kTime{"a time unit", {{"s", 1.0}, {"ms", 1e-3}, {"us", 1e-6}, {"ns", 1e-9}}};
const UnitTable kRate{"an angular rate unit", {{"rad/s", 1.0}, {"deg/s", fsw::kDegToRad}}};
const UnitTable kAngle{"an angle unit", {{"rad", 1.0}, {"deg", fsw::kDegToRad}, {"1e-7 deg", 1e-7 * fsw::kDegToRad}}};
const UnitTable kAccel{"an acceleration unit", {{"m/s^2", 1.0}, {"g", fsw::kStandardGravity_mps2}}};
const UnitTable kDeltaV{"a velocity increment unit", {{"m/s", 1.0}, {"mm/s", 1e-3}}};
const UnitTable kLength{"a length unit", {{"m", 1.0}, {"mm", 1e-3}, {"cm", 1e-2}}};
const UnitTable kSpeed{"a speed unit", {{"m/s", 1.0}, {"mm/s", 1e-3}, {"cm/s", 1e-2}, {"km/h", 1.0 / 3.6}}};
const UnitTable kRangeRate{"a range-rate unit", {{"m/s", 1.0}, {"-m/s", -1.0}, {"Hz", -kGpsL1Wavelength_m}}};

const std::vector<std::pair<std::string_view, int>> kKinds{
    {"none", 0}, {"fixed", 1}, {"float", 2}, {"sbas", 3}, {"dgps", 4}, {"single", 5}, {"ppp", 6}, {"dr", 7}};

class DescriptionReader : public ts::Reader {
 public:
  DescriptionReader(std::string source, std::string base) : Reader(std::move(source)), base_(std::move(base)) {}

  bool file(const toml::table& root, RecordingDescription& d) {
    if (!fields(root, "", {{"name", text(d.name)},
                           {"description", text(d.description)},
                           {"clip_gnss_to_imu", boolean(d.clip_gnss_to_imu)},
                           {"max_fit_error_m", number(d.max_fit_error_m, ts::positive())},
                           {"imu", sub([&](const toml::table& t, const std::string& p) { return imu(t, p, d.imu); })},
                           {"gnss", sub([&](const toml::table& t, const std::string& p) { return gnss(t, p, d.gnss); })},
                           {"gnss_raw", sub([&](const toml::table& t, const std::string& p) { return raw(t, p, d.raw); })},
                           {"reference",
                            sub([&](const toml::table& t, const std::string& p) { return reference(t, p, d.reference); })}}))
      return false;
    if (!d.imu.present && !d.gnss.present && !d.raw.present && !d.reference.present)
      return fail(root, "the description names no stream: give at least one of [imu], [gnss], [gnss_raw], [reference]");
    if (d.reference.present && d.reference.from_gnss && !d.gnss.present)
      return fail(root, "'reference.from' = \"gnss\" needs a [gnss] stream");
    if (d.imu.present && d.imu.time.base == TimeBase::kLocal && !(d.gnss.present && d.gnss.local_clock.set()))
      return fail(root, "'imu.time.base' = \"local\" needs the clock pair: 'gnss.local_clock' on the GNSS rows");
    if (d.reference.present && !d.reference.from_gnss && d.reference.time.base == TimeBase::kLocal &&
        !(d.gnss.present && d.gnss.local_clock.set()))
      return fail(root, "'reference.time.base' = \"local\" needs the clock pair: 'gnss.local_clock' on the GNSS rows");
    return true;
  }

 private:
  using TableFn = std::function<bool(const toml::table&, const std::string&)>;
  Handler sub(TableFn fn) {
    return [this, fn](const toml::node& n, const std::string& p) {
      const toml::table* t = table(n, p);
      return t != nullptr && fn(*t, p + ".");
    };
  }

  /// A string key that must be one of options.
  Handler one_of(std::string& out, std::vector<std::string> options) {
    return [this, &out, options](const toml::node& n, const std::string& p) {
      std::string expected;
      for (std::size_t i = 0; i < options.size(); ++i) {
        if (const auto* v = n.as_string(); v && v->get() == options[i]) {
          out = options[i];
          return true;
        }
        expected += (i == 0 ? "" : i + 1 == options.size() ? " or " : ", ") + ("\"" + options[i] + "\"");
      }
      return fail(n, "'" + p + "' must be " + expected + got(n));
    };
  }

  /// A file name, resolved against the description's directory.
  Handler path(std::string& out) {
    return [this, &out](const toml::node& n, const std::string& p) {
      const auto* v = n.as_string();
      if (!v || v->get().empty()) return fail(n, "'" + p + "' must be a file name" + got(n));
      out = resolve(v->get());
      return true;
    };
  }
  std::string resolve(const std::string& f) const {
    const std::filesystem::path fp(f);
    return fp.is_absolute() || base_.empty() ? f : (std::filesystem::path(base_) / fp).string();
  }

  bool column_of(const toml::node& n, const std::string& p, ColumnRef& out) {
    if (const auto* s = n.as_string(); s && !s->get().empty()) {
      out = ColumnRef{s->get(), -1};
      return true;
    }
    if (const auto* i = n.as_integer(); i && i->get() >= 1 && i->get() <= 10000) {
      out = ColumnRef{"", static_cast<int>(i->get() - 1)};
      return true;
    }
    return fail(n, "'" + p + "' must be a column: a header name (string) or a 1-based column number (1..10000)" + got(n));
  }
  Handler column(ColumnRef& out) {
    return [this, &out](const toml::node& n, const std::string& p) { return column_of(n, p, out); };
  }
  Handler columns3(std::array<ColumnRef, 3>& out) {
    return [this, &out](const toml::node& n, const std::string& p) {
      const auto* a = n.as_array();
      if (!a || a->size() != 3) return fail(n, "'" + p + "' must be an array of 3 columns (names or 1-based numbers)" + got(n));
      for (std::size_t i = 0; i < 3; ++i)
        if (!column_of(*a->get(i), p + "[" + std::to_string(i) + "]", out[i])) return false;
      return true;
    };
  }
  Handler unit(const UnitTable& u, std::string& name, double& scale) {
    return [this, &u, &name, &scale](const toml::node& n, const std::string& p) {
      std::string expected;
      for (std::size_t i = 0; i < u.units.size(); ++i) {
        if (const auto* s = n.as_string(); s && s->get() == u.units[i].first) {
          name = s->get();
          scale = u.units[i].second;
          return true;
        }
        expected += (i == 0 ? "" : i + 1 == u.units.size() ? " or " : ", ") + ("\"" + std::string(u.units[i].first) + "\"");
      }
      return fail(n, "'" + p + "' must be " + std::string(u.what) + ": " + expected + got(n));
    };
  }
  Handler vec3(Vec3Columns& v, const UnitTable* u) {
    return [this, &v, u](const toml::node& n, const std::string& p) {
      const toml::table* t = table(n, p);
      if (t == nullptr) return false;
      if (!fields(*t, p + ".", {{"columns", columns3(v.cols)}, {"unit", unit(*u, v.unit, v.scale)}})) return false;
      if (!v.set()) return fail(n, "'" + p + ".columns' is required");
      return true;
    };
  }
  /// { column = ..., unit = ... } of one quantity.
  Handler scalar(ColumnRef& c, const UnitTable& u, std::string& unit_name, double& scale) {
    return [this, &c, &u, &unit_name, &scale](const toml::node& n, const std::string& p) {
      if (n.is_string() || n.is_integer()) return column_of(n, p, c);
      const toml::table* t = table(n, p);
      if (t == nullptr) return false;
      if (!fields(*t, p + ".", {{"column", column(c)}, {"unit", unit(u, unit_name, scale)}})) return false;
      if (!c.set()) return fail(n, "'" + p + ".column' is required");
      return true;
    };
  }

  bool layout_key(const toml::table& t, const std::string& p, TableLayout& l, bool& handled, const std::string& key,
                  const toml::node& n) {
    handled = true;
    const std::string kp = p + key;
    if (key == "file") {
      std::string f;
      if (!path(f)(n, kp)) return false;
      l.files = {f};
      return true;
    }
    if (key == "files") {
      const auto* a = n.as_array();
      if (!a || a->empty()) return fail(n, "'" + kp + "' must be a non-empty array of file names" + got(n));
      l.files.clear();
      for (std::size_t i = 0; i < a->size(); ++i) {
        std::string f;
        if (!path(f)(*a->get(i), kp + "[" + std::to_string(i) + "]")) return false;
        l.files.push_back(f);
      }
      return true;
    }
    if (key == "format") {
      const auto* s = n.as_string();
      if (!s || (s->get() != "csv" && s->get() != "whitespace"))
        return fail(n, "'" + kp + "' must be \"csv\" or \"whitespace\"" + got(n));
      l.whitespace = s->get() == "whitespace";
      return true;
    }
    if (key == "delimiter") {
      const auto* s = n.as_string();
      if (!s || s->get().size() != 1 || s->get() == "\n" || s->get() == "\r")
        return fail(n, "'" + kp + "' must be one character, e.g. \",\" or \";\"" + got(n));
      l.delimiter = s->get()[0];
      return true;
    }
    if (key == "header") return boolean(l.header)(n, kp);
    if (key == "whitespace") return boolean(l.whitespace)(n, kp);
    if (key == "skip_lines") return integer(l.skip_lines, 0, 1000)(n, kp);
    if (key == "fields") return integer(l.fields, 1, 10000)(n, kp);
    if (key == "comment") {
      const auto* s = n.as_string();
      if (!s || s->get().empty() || s->get().size() > 8) return fail(n, "'" + kp + "' must be a short prefix such as \"#\"" + got(n));
      l.comment = s->get();
      return true;
    }
    (void)t;
    handled = false;
    return true;
  }

  bool time(const toml::table& t, const std::string& p, TimeSpec& s) {
    std::string week_from;
    if (!fields(t, p, {{"column", column(s.column)},
                       {"unit", unit(kTime, s.unit, s.scale_s)},
                       {"base", choice(s.base, {{"gps_tow", TimeBase::kGpsTow},
                                                {"gps_seconds", TimeBase::kGpsSeconds},
                                                {"unix", TimeBase::kUnix},
                                                {"local", TimeBase::kLocal},
                                                {"rtklib_tag", TimeBase::kRtklibTag}})},
                       {"week", integer(s.week, 0, 10000)},
                       {"week_column", column(s.week_column)},
                       {"week_from", one_of(week_from, {"ephemeris"})},
                       {"tag_file", path(s.tag_file)},
                       {"clock_ratio", number(s.clock_ratio, ts::closed(0.99, 1.01))}}))
      return false;
    if (!s.column.set()) return fail(t, "'" + p + "column' is required (the time column)");
    if (!week_from.empty()) {
      if (week_from != "ephemeris") return fail(t, "'" + p + "week_from' must be \"ephemeris\" (got \"" + week_from + "\")");
      s.week_from_ephemeris = true;
    }
    if (s.base == TimeBase::kGpsTow && s.week < 0 && !s.week_column.set() && !s.week_from_ephemeris)
      return fail(t, "'" + p + "base' = \"gps_tow\" needs the week: 'week', 'week_column' or 'week_from' = \"ephemeris\"");
    if (s.base == TimeBase::kRtklibTag && s.tag_file.empty())
      return fail(t, "'" + p + "base' = \"rtklib_tag\" needs 'tag_file'");
    return true;
  }
  Handler time_table(TimeSpec& s) {
    return [this, &s](const toml::node& n, const std::string& p) {
      const toml::table* t = table(n, p);
      return t != nullptr && time(*t, p + ".", s);
    };
  }

  /// fields() with a first handler for shared keys (table layout, position columns): it sets
  /// handled when the key was its own.
  using Extra = std::function<bool(const std::string& key, const toml::node& n, const std::string& path, bool& handled)>;
  bool fields_with(const toml::table& t, const std::string& prefix, const Extra& extra, std::initializer_list<Field> known) {
    for (auto&& [key, node] : t) {
      const std::string kp = prefix + std::string(key.str());
      bool handled = false;
      if (!extra(std::string(key.str()), node, kp, handled)) return false;
      if (handled) continue;
      const std::string_view name = key.str();
      const auto field = std::find_if(known.begin(), known.end(), [&](const Field& f) { return f.key == name; });
      if (field == known.end()) return fail(key, "unknown key '" + kp + "'");
      if (!field->handle(node, kp)) return false;
    }
    return true;
  }
  Extra layout_keys(const toml::table& t, const std::string& p, TableLayout& l) {
    return [this, &t, &p, &l](const std::string& key, const toml::node& n, const std::string&, bool& handled) {
      return layout_key(t, p, l, handled, key, n);
    };
  }
  Extra layout_and_position(const toml::table& t, const std::string& p, TableLayout& l, PositionColumns& pc) {
    return [this, &t, &p, &l, &pc](const std::string& key, const toml::node& n, const std::string& kp, bool& handled) {
      if (!layout_key(t, p, l, handled, key, n)) return false;
      if (handled) return true;
      return position(key, n, kp, pc, handled);
    };
  }

  bool position(const std::string& key, const toml::node& n, const std::string& p, PositionColumns& pc, bool& handled) {
    handled = true;
    if (key == "lat") return scalar(pc.lat, kAngle, pc.angle_unit, pc.angle_scale)(n, p);
    if (key == "lon") return scalar(pc.lon, kAngle, pc.angle_unit, pc.angle_scale)(n, p);
    if (key == "height") {
      if (n.is_string() || n.is_integer()) return column_of(n, p, pc.height);
      const toml::table* t = table(n, p);
      if (t == nullptr) return false;
      if (!fields(*t, p + ".", {{"column", column(pc.height)},
                                {"unit", unit(kLength, pc.height_unit, pc.height_scale)},
                                {"datum", choice(pc.datum, {{"ellipsoid", HeightDatum::kEllipsoid},
                                                            {"msl_egm96", HeightDatum::kMslEgm96}})}}))
        return false;
      if (!pc.height.set()) return fail(n, "'" + p + ".column' is required");
      return true;
    }
    if (key == "velocity") {
      const toml::table* t = table(n, p);
      if (t == nullptr) return false;
      std::string vertical = "up";
      pc.vel.unit = "m/s";
      if (!fields(*t, p + ".", {{"form", choice(pc.velocity, {{"enu", VelocityForm::kEnu},
                                                                {"ned", VelocityForm::kNed},
                                                                {"ecef", VelocityForm::kEcef},
                                                                {"speed_course", VelocityForm::kSpeedCourse}})},
                                {"columns", columns3(pc.vel.cols)},
                                {"unit", unit(kSpeed, pc.vel.unit, pc.vel.scale)},
                                {"course_unit", unit(kAngle, pc.course_unit, pc.course_scale)},
                                {"vertical_positive", one_of(vertical, {"up", "down"})}}))
        return false;
      if (pc.velocity == VelocityForm::kNone) return fail(n, "'" + p + ".form' is required (enu, ned, ecef or speed_course)");
      if (!pc.vel.set()) return fail(n, "'" + p + ".columns' is required");
      if (vertical != "up" && vertical != "down")
        return fail(n, "'" + p + ".vertical_positive' must be \"up\" or \"down\" (got \"" + vertical + "\")");
      pc.vertical_sign = vertical == "up" ? 1.0 : -1.0;
      return true;
    }
    handled = false;
    return true;
  }

  bool imu(const toml::table& t, const std::string& p, ImuStreamSpec& s) {
    s.present = true;
    s.origin = "description";
    std::string kind = "rates";
    double max_gyro_dps = s.max_gyro_radps / fsw::kDegToRad;
    std::vector<double> rot;
    std::array<double, 3> r{0, 0, 0};
    bool have_rot = false;
    if (const auto* k = t.get("kind"); k && k->is_string()) kind = k->as_string()->get();
    if (!fields_with(t, p, layout_keys(t, p, s.table),
                     {{"kind", one_of(kind, {"rates", "increments"})},
                      {"time", time_table(s.time)},
                      {"gyro", [&](const toml::node& n, const std::string& q) { return vec3(s.gyro, kind == "increments" ? &kAngle : &kRate)(n, q); }},
                      {"accel", [&](const toml::node& n, const std::string& q) { return vec3(s.accel, kind == "increments" ? &kDeltaV : &kAccel)(n, q); }},
                      {"axes", text(s.axes)},
                      {"rotation_deg", [&](const toml::node& n, const std::string& q) { have_rot = true; return vector3(r, ts::closed(-360, 360))(n, q); }},
                      {"max_accel_mps2", number(s.max_accel_mps2, ts::positive())},
                      {"max_gyro_dps", number(max_gyro_dps, ts::positive())}}))
      return false;
    if (kind != "rates" && kind != "increments")
      return fail(t, "'" + p + "kind' must be \"rates\" or \"increments\" (got \"" + kind + "\")");
    s.increments = kind == "increments";
    s.max_gyro_radps = max_gyro_dps * fsw::kDegToRad;
    s.has_rotation = have_rot;
    s.rotation_rpy_deg = r;
    if (s.table.files.empty()) return fail(t, "'" + p + "file' is required");
    if (!s.gyro.set() || !s.accel.set()) return fail(t, "'" + p + "gyro' and '" + p + "accel' are required");
    if (!s.time.column.set()) return fail(t, "'" + p + "time' is required");
    if (s.time.base == TimeBase::kGpsTow && s.time.week < 0 && s.time.week_from_ephemeris) {
      // resolved by the engine from the raw stream's ephemerides
    }
    try {
      parse_axis_map(s.axes);
    } catch (const std::exception& e) {
      return fail(t, "'" + p + "axes' = \"" + s.axes + "\": " + e.what());
    }
    return true;
  }

  bool gnss(const toml::table& t, const std::string& p, GnssStreamSpec& s) {
    s.present = true;
    std::string format = "table";
    bool time_given = false;
    const Extra shared = layout_and_position(t, p, s.table, s.pos);
    const Extra extra = [&](const std::string& key, const toml::node& n, const std::string& kp, bool& handled) {
      if (key == "format") {
        handled = true;
        const auto* v = n.as_string();
        if (!v || (v->get() != "table" && v->get() != "rtklib_pos" && v->get() != "csv" && v->get() != "whitespace"))
          return fail(n, "'" + kp + "' must be \"csv\", \"whitespace\" or \"rtklib_pos\"" + got(n));
        if (v->get() == "rtklib_pos") {
          format = "rtklib_pos";
          return true;
        }
      }
      handled = false;
      return shared(key, n, kp, handled);
    };
    std::string vel_sigma_unit;
    double sigma_scale_unused = 1.0;
    if (!fields_with(t, p, extra, {{"time", [&](const toml::node& n, const std::string& q) { time_given = true; return time_table(s.time)(n, q); }},
                          {"local_clock", scalar(s.local_clock, kTime, s.local_unit, s.local_scale_s)},
                          {"latency_s", number(s.latency_s, ts::closed(-5.0, 5.0))},
                          {"pos_sigma", vec3(s.pos_sigma, &kLength)},
                          {"sigma_model", sub([&](const toml::table& m, const std::string& q) { return sigma_model(m, q, s); })},
                          {"vel_sigma", vec3(s.vel_sigma, &kSpeed)},
                          {"vel_sigma_mps", number(s.vel_sigma_mps, ts::positive())},
                          {"quality", [&](const toml::node& n, const std::string& q) { return quality(n, q, s); }},
                          {"satellites", column(s.n_sat)}}))
      return false;
    (void)vel_sigma_unit;
    (void)sigma_scale_unused;
    s.format = format;
    if (s.table.files.empty()) return fail(t, "'" + p + "file' is required");
    if (format == "rtklib_pos") return true;
    if (!time_given) return fail(t, "'" + p + "time' is required");
    if (!s.pos.lat.set() || !s.pos.lon.set() || !s.pos.height.set())
      return fail(t, "'" + p + "lat', '" + p + "lon' and '" + p + "height' are required");
    if (!s.pos_sigma.set() && s.uere_m <= 0.0 && s.uere_by_kind.empty())
      return fail(t, "the GNSS sigmas: give '" + p + "pos_sigma' columns or a '" + p + "sigma_model'");
    if (s.time.base == TimeBase::kLocal)
      return fail(t, "'" + p + "time.base' = \"local\": the GNSS rows carry the GPS time the clock pair is fitted to; "
                     "give their GPS time as 'time' and the local clock as '" + p + "local_clock'");
    return true;
  }

  bool sigma_model(const toml::table& t, const std::string& p, GnssStreamSpec& s) {
    const toml::table* by = nullptr;
    if (!fields(t, p, {{"hdop", column(s.hdop)},
                       {"vdop", column(s.vdop)},
                       {"uere_m", number(s.uere_m, ts::positive())},
                       {"uere_by_kind_m", [&](const toml::node& n, const std::string& q) { by = table(n, q); return by != nullptr; }}}))
      return false;
    if (by != nullptr) {
      for (auto&& [k, n] : *by) {
        const std::string name(k.str());
        const auto it = std::find_if(kKinds.begin(), kKinds.end(), [&](const auto& e) { return e.first == name; });
        if (it == kKinds.end())
          return fail(k, "'" + p + "uere_by_kind_m." + name + "': unknown solution kind (fixed, float, sbas, dgps, single, ppp, dr)");
        double v = 0.0;
        if (!read_number(n, p + "uere_by_kind_m." + name, ts::positive(), v)) return false;
        s.uere_by_kind[it->second] = v;
      }
    }
    if (!s.hdop.set()) return fail(t, "'" + p + "hdop' is required (the HDOP column)");
    if (s.uere_m <= 0.0 && s.uere_by_kind.empty()) return fail(t, "'" + p + "uere_m' or '" + p + "uere_by_kind_m' is required");
    return true;
  }

  bool kind_of(const toml::node& n, const std::string& p, int& out) {
    for (const auto& [name, v] : kKinds)
      if (const auto* s = n.as_string(); s && s->get() == name) {
        out = v;
        return true;
      }
    return fail(n, "'" + p + "' must be a solution kind: \"fixed\", \"float\", \"sbas\", \"dgps\", \"single\", \"ppp\", \"dr\" or \"none\"" + got(n));
  }

  bool quality(const toml::node& n, const std::string& p, GnssStreamSpec& s) {
    if (n.is_string()) return kind_of(n, p, s.quality_default);
    const toml::table* t = table(n, p);
    if (t == nullptr) return false;
    const toml::table* map = nullptr;
    if (!fields(*t, p + ".", {{"column", column(s.quality)},
                              {"map", [&](const toml::node& m, const std::string& q) { map = table(m, q); return map != nullptr; }}}))
      return false;
    if (!s.quality.set()) return fail(n, "'" + p + ".column' is required");
    if (map == nullptr) return true;  // the column holds the kinds' numbers (RTKLIB Q)
    for (auto&& [k, v] : *map) {
      const std::string key(k.str());
      char* end = nullptr;
      const long code = std::strtol(key.c_str(), &end, 10);
      if (key.empty() || *end != '\0') return fail(k, "'" + p + ".map." + key + "': the key must be the column's integer value");
      int kind = 0;
      if (!kind_of(v, p + ".map." + key, kind)) return false;
      s.quality_map[code] = kind;
    }
    return true;
  }

  bool raw(const toml::table& t, const std::string& p, RawStreamSpec& s) {
    s.present = true;
    std::string fmt = "rinex3";
    if (const auto* f = t.get("format")) {
      const auto* v = f->as_string();
      if (!v || (v->get() != "rinex3" && v->get() != "ubx" && v->get() != "table"))
        return fail(*f, "'" + p + "format' must be \"rinex3\", \"ubx\" or \"table\"" + got(*f));
      fmt = v->get();
    }
    const Extra lay = layout_keys(t, p, s.table);
    const Extra extra = [&](const std::string& key, const toml::node& n, const std::string& kp, bool& handled) {
      if (key == "format") {
        handled = true;
        return true;
      }
      if (key == "delimiter" || key == "header" || key == "skip_lines" || key == "fields" || key == "comment" ||
          key == "file" || key == "files" || key == "whitespace")
        return lay(key, n, kp, handled);
      handled = false;
      return true;
    };
    s.format = fmt == "rinex3" ? RawFormat::kRinex3 : fmt == "ubx" ? RawFormat::kUbx : RawFormat::kTable;
    std::string pr_unit, cn0_unit;
    double pr_scale = 1.0, cn0_scale = 1.0;
    if (!fields_with(t, p, extra, {{"obs", path(s.obs_file)},
                          {"nav", path(s.nav_file)},
                          {"ubx", path(s.ubx_file)},
                          {"convbin", text(s.convbin)},
                          {"keep_temp", boolean(s.keep_temp)},
                          {"time", time_table(s.time)},
                          {"prn", column(s.prn)},
                          {"pseudorange", scalar(s.pseudorange, kLength, pr_unit, pr_scale)},
                          {"range_rate", scalar(s.range_rate, kRangeRate, s.range_rate_unit, s.range_rate_scale)},
                          {"cn0", column(s.cn0)},
                          {"ephemeris", sub([&](const toml::table& e, const std::string& q) {
                             return fields(e, q, {{"file", path(s.ephemeris_file)},
                                                  {"format", one_of(s.ephemeris_format, {"csv", "rinex3"})}});
                           })}}))
      return false;
    (void)cn0_unit;
    (void)cn0_scale;
    if (pr_scale != 1.0) return fail(t, "'" + p + "pseudorange.unit' must be \"m\"");
    switch (s.format) {
      case RawFormat::kRinex3:
        if (s.obs_file.empty() || s.nav_file.empty()) return fail(t, "'" + p + "format' = \"rinex3\" needs 'obs' and 'nav'");
        break;
      case RawFormat::kUbx:
        if (s.ubx_file.empty()) return fail(t, "'" + p + "format' = \"ubx\" needs 'ubx' (converted by RTKLIB's convbin)");
        break;
      case RawFormat::kTable:
        if (s.table.files.empty()) return fail(t, "'" + p + "file' is required");
        if (!s.time.column.set() || !s.prn.set() || !s.pseudorange.set() || !s.range_rate.set())
          return fail(t, "'" + p + "time', 'prn', 'pseudorange' and 'range_rate' are required for a table");
        if (s.ephemeris_file.empty()) return fail(t, "'" + p + "ephemeris.file' is required for a table");
        if (s.ephemeris_format != "csv" && s.ephemeris_format != "rinex3")
          return fail(t, "'" + p + "ephemeris.format' must be \"csv\" or \"rinex3\" (got \"" + s.ephemeris_format + "\")");
        break;
    }
    return true;
  }

  bool reference(const toml::table& t, const std::string& p, ReferenceStreamSpec& s) {
    s.present = true;
    bool time_given = false;
    std::string from = "table";
    double att_scale = fsw::kDegToRad;
    if (!fields_with(t, p, layout_and_position(t, p, s.table, s.pos), {{"kind", text(s.kind)},
                          {"from", one_of(from, {"table", "gnss"})},
                          {"max_quality", integer(s.max_quality, 1, 7)},
                          {"time", [&](const toml::node& n, const std::string& q) { time_given = true; return time_table(s.time)(n, q); }},
                          {"attitude", vec3(s.attitude, &kAngle)}}))
      return false;
    (void)att_scale;
    if (s.kind.empty()) return fail(t, "'" + p + "kind' must name what the reference is (rtk, autopilot_estimate, post_processed_ins, simulation, ...)");
    if (from != "table" && from != "gnss") return fail(t, "'" + p + "from' must be \"table\" or \"gnss\" (got \"" + from + "\")");
    s.from_gnss = from == "gnss";
    if (s.from_gnss) return true;
    if (s.table.files.empty()) return fail(t, "'" + p + "file' is required (or 'from' = \"gnss\")");
    if (!time_given) return fail(t, "'" + p + "time' is required");
    if (!s.pos.lat.set() || !s.pos.lon.set() || !s.pos.height.set())
      return fail(t, "'" + p + "lat', '" + p + "lon' and '" + p + "height' are required");
    return true;
  }

  std::string base_;
};

}  // namespace

const char* to_string(TimeBase b) {
  switch (b) {
    case TimeBase::kGpsTow: return "gps_tow";
    case TimeBase::kGpsSeconds: return "gps_seconds";
    case TimeBase::kUnix: return "unix";
    case TimeBase::kLocal: return "local";
    case TimeBase::kRtklibTag: return "rtklib_tag";
  }
  return "?";
}

std::vector<std::string> description_inputs(const RecordingDescription& d) {
  std::vector<std::string> v;
  const auto add = [&](const std::string& f) {
    if (!f.empty()) v.push_back(f);
  };
  for (const auto* l : {&d.imu.table, &d.gnss.table, &d.raw.table, &d.reference.table})
    for (const std::string& f : l->files) add(f);
  for (const std::string& f : {d.imu.time.tag_file, d.raw.obs_file, d.raw.nav_file, d.raw.ubx_file, d.raw.ephemeris_file})
    add(f);
  return v;
}

DescriptionParseResult parse_recording_description_text(const std::string& text, const std::string& source,
                                                         const std::string& base_dir, RecordingDescription& out) {
  toml::table root;
  std::string error;
  if (!ts::parse_document(text, source, root, error)) return {false, error};
  RecordingDescription d;
  d.source = source;
  d.base_dir = base_dir;
  DescriptionReader r(source, base_dir);
  if (!r.file(root, d)) return {false, r.error()};
  out = std::move(d);
  return {true, ""};
}

DescriptionParseResult parse_recording_description_file(const std::string& path, const std::string& data_dir,
                                                        RecordingDescription& out) {
  const std::string bad = hal::check_input_file(path, 1 << 20);
  if (!bad.empty()) return {false, bad};
  std::ifstream in(path, std::ios::binary);
  if (!in) return {false, path + ": cannot open the recording description"};
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string base = !data_dir.empty() ? data_dir : std::filesystem::path(path).parent_path().string();
  return parse_recording_description_text(ss.str(), path, base, out);
}

}  // namespace tools
