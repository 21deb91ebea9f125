// Flight configuration TOML reader (flight_config.hpp; schema in config/README.md; validation in
// validate.cpp, the loader in load.cpp, the keys and their unit conversion in keys.cpp).
#include "cfg/flight_config.hpp"

#include <cmath>
#include <tuple>

#include "cfg/effect_names.hpp"
#include "cfg/text_file.hpp"
#include "cfg/toml_schema.hpp"
#include "fsw/gnss.hpp"
#include "keys.hpp"

namespace cfg {

const char* to_string(GnssSource s) { return s == GnssSource::kPvt ? "pvt" : "raw"; }

namespace {

using toml_schema::closed;
using toml_schema::got;
using toml_schema::left_open;
using toml_schema::non_negative;
using toml_schema::positive;
using toml_schema::Range;

/// Values read in the file's units; converted into the FlightAppConfig after the whole file parsed.
struct Units {
  std::optional<double> nav_rate_hz, ekf_rate_hz, gnss_wait_s;
  std::optional<double> vrw_mps_per_rthr, arw_deg_per_rthr, vrw_mps_per_rts, arw_rad_per_rts;
  std::optional<double> accel_bias_sigma_mg, gyro_bias_sigma_degph;
  std::optional<double> clock_h0_s, clock_h_minus2_per_s;
  std::optional<double> accel_scale_ppm, gyro_scale_ppm, accel_mis_arcsec, gyro_mis_arcsec;
  std::optional<double> heading_offset_deg, roll_pitch_sigma_deg, heading_sigma_deg;
  std::optional<double> static_max_rate_dev_dps, vm_max_heading_sigma_deg;
};


using F = fsw::ConfigField;
using keys::alt_to_si;
using keys::to_si;

/// Records the file as the setter of every key of the table (arrays are values).
void note_keys(const toml::table& t, const std::string& prefix, const std::string& file,
               std::map<std::string, std::string>& out) {
  for (auto&& [key, node] : t) {
    const std::string path = prefix + std::string(key.str());
    if (const toml::table* sub = node.as_table())
      note_keys(*sub, path + ".", file, out);
    else
      out[path] = file;
  }
}


class Parser : public toml_schema::Reader {
 public:
  using Reader::Reader;

  bool file(const toml::table& root, FlightConfig& c, Units& u) {
    fsw::FlightAppConfig& a = c.app;
    fsw::ExecutiveConfig& x = a.exec;
    fsw::EkfConfig& e = a.exec.ekf;
    return fields(root, "", {
        {"name", text(c.name)},
        {"description", text(c.description)},
        {"executive", [&](const toml::node& n, const std::string& p) {
           const toml::table* t = table(n, p);
           return t && fields(*t, p + ".", {
               {"imu_samples_per_frame", integer(x.imu_samples_per_frame, 1, fsw::FrameBuilder::kMaxSamplesPerFrame)},
               {"nav_rate_hz", opt(u.nav_rate_hz, left_open(0.0, 2000.0))},
               {"ekf_rate_hz", opt(u.ekf_rate_hz, left_open(0.0, 100.0))},
               {"gnss_wait_s", opt(u.gnss_wait_s, closed(0.0, 10.0))},
               {"max_gnss_age_s", number(x.max_gnss_age_s, closed(0.0, 10.0))},
               {"frame_budget_s", number(x.frame_budget_s, left_open(0.0, 1.0))},
               {"propagation_substep_frames", integer(e.propagation_substep_frames, 1, 1000)},
               {"ekf_latency_frames", integer(x.ekf_latency_frames, 1, 1000)},
           });
         }},
        {"gnss", [&](const toml::node& n, const std::string& p) {
           const toml::table* t = table(n, p);
           return t && fields(*t, p + ".", {
               {"source", choice(c.gnss_source, {{"raw", GnssSource::kRaw}, {"pvt", GnssSource::kPvt}})},
               {"pvt_max_quality", integer(a.pvt_max_quality, 1, 7)},
               {"pvt_sigma_scale", number(e.pvt_sigma_scale, positive())},
               {"pvt_pos_sigma_floor_m", number(e.pvt_pos_sigma_floor_m, non_negative())},
               {"pvt_vel_sigma_floor_mps", number(e.pvt_vel_sigma_floor_mps, non_negative())},
               {"pseudorange_sigma_m", number(e.pseudorange_sigma_m, positive())},
               {"pseudorange_rate_sigma_mps", number(e.pseudorange_rate_sigma_mps, positive())},
               {"use_pseudorange_rate", boolean(e.use_pseudorange_rate)},
               {"range_error_sigma_m", number(e.range_gm_sigma_m, positive())},
               {"range_error_tau_s", number(e.range_gm_tau_s, positive())},
               {"range_rate_error_sigma_mps", number(e.range_rate_gm_sigma_mps, positive())},
               {"range_rate_error_tau_s", number(e.range_rate_gm_tau_s, positive())},
               {"gate_chi2", number(e.gate_chi2, positive())},
               {"clock_bias_sigma_m", number(e.clock_bias_sigma_m, positive())},
               {"clock_drift_sigma_mps", number(e.clock_drift_sigma_mps, positive())},
               {"clock_h0_s", opt(u.clock_h0_s, non_negative())},
               {"clock_h_minus2_per_s", opt(u.clock_h_minus2_per_s, non_negative())},
           });
         }},
        {"imu", [&](const toml::node& n, const std::string& p) {
           const toml::table* t = table(n, p);
           return t && fields(*t, p + ".", {
               {"vrw_mps_per_rthr", opt(u.vrw_mps_per_rthr, non_negative())},
               {"arw_deg_per_rthr", opt(u.arw_deg_per_rthr, non_negative())},
               {"vrw_mps_per_rts", opt(u.vrw_mps_per_rts, non_negative())},
               {"arw_rad_per_rts", opt(u.arw_rad_per_rts, non_negative())},
               {"accel_bias_sigma_mg", opt(u.accel_bias_sigma_mg, non_negative())},
               {"gyro_bias_sigma_degph", opt(u.gyro_bias_sigma_degph, non_negative())},
               {"accel_bias_rw_mps2_per_rts", number(e.accel_bias_rw_mps2_per_rts, non_negative())},
               {"gyro_bias_rw_radps_per_rts", number(e.gyro_bias_rw_radps_per_rts, non_negative())},
               {"accel_scale_factor_sigma_ppm", opt(u.accel_scale_ppm, non_negative())},
               {"gyro_scale_factor_sigma_ppm", opt(u.gyro_scale_ppm, non_negative())},
               {"accel_misalignment_sigma_arcsec", opt(u.accel_mis_arcsec, non_negative())},
               {"gyro_misalignment_sigma_arcsec", opt(u.gyro_mis_arcsec, non_negative())},
           });
         }},
        {"init", [&](const toml::node& n, const std::string& p) {
           const toml::table* t = table(n, p);
           return t && fields(*t, p + ".", {
               {"min_satellites", integer(a.min_satellites_for_init, 4, fsw::kMaxGnssChannels)},
               {"max_pdop", number(a.max_init_pdop, positive())},
               {"min_speed_mps", number(a.min_init_speed_mps, non_negative())},
               {"heading_offset_deg", opt(u.heading_offset_deg, closed(-180.0, 180.0))},
               {"levelling_samples", integer(a.levelling_samples, 1, 1024)},
               {"pos_sigma_m", number(a.init_pos_sigma_m, positive())},
               {"vel_sigma_mps", number(a.init_vel_sigma_mps, positive())},
               {"roll_pitch_sigma_deg", opt(u.roll_pitch_sigma_deg, left_open(0.0, 90.0))},
               {"heading_sigma_deg", opt(u.heading_sigma_deg, left_open(0.0, 180.0))},
               {"mode", choice(a.init_mode, {{"track", fsw::InitMode::kTrack},
                                             {"static", fsw::InitMode::kStatic},
                                             {"velocity_matching", fsw::InitMode::kVelocityMatching}})},
               {"alignment_s", number(a.alignment_s, left_open(0.0, 3600.0))},
               {"static_max_speed_mps", number(a.static_max_speed_mps, closed(0.0, 10.0))},
               {"static_max_rate_dev_dps", opt(u.static_max_rate_dev_dps, left_open(0.0, 100.0))},
               {"static_max_accel_dev_mps2", number(a.static_max_accel_dev_mps2, left_open(0.0, 100.0))},
               {"vm_min_s", number(a.vm_min_s, closed(0.0, 600.0))},
               {"vm_max_s", number(a.vm_max_s, left_open(0.0, 600.0))},
               {"vm_max_heading_sigma_deg", opt(u.vm_max_heading_sigma_deg, left_open(0.0, 180.0))},
               {"vm_rest_gyro_bias", boolean(a.vm_rest_gyro_bias)},
               {"vm_rest_min_s", number(a.vm_rest_min_s, closed(0.0, 600.0))},
           });
         }},
        {"mounting", [&](const toml::node& n, const std::string& p) {
           const toml::table* t = table(n, p);
           return t && fields(*t, p + ".", {{"lever_arm_b_m", vector3(e.lever_arm_b_m, closed(-100.0, 100.0))}});
         }},
        {"health", [&](const toml::node& n, const std::string& p) {
           const toml::table* t = table(n, p);
           return t && fields(*t, p + ".", {
               {"nis_window_epochs", integer(e.nis_window, 1, 1000)},
               {"runaway_epochs", integer(e.runaway_epochs, 0, 1000)},
           });
         }},
        {"diagnosis", [&](const toml::node& n, const std::string& p) { return diagnosis(n, p, c); }},
    });
  }

 private:
  Handler opt(std::optional<double>& out, Range range) {
    return [this, &out, range](const toml::node& n, const std::string& p) {
      double v = 0.0;
      if (!read_number(n, p, range, v)) return false;
      out = v;
      return true;
    };
  }

  bool diagnosis(const toml::node& n, const std::string& path, FlightConfig& c) {
    const toml::table* t = table(n, path);
    return t && fields(*t, path + ".", {
        {"outage_length_s", opt(c.outage_length_s, non_negative())},
        {"outage_period_s", opt(c.outage_period_s, positive())},
        {"outage_first_s", opt(c.outage_first_s, non_negative())},
        {"gain_skip_s", opt(c.gain_skip_s, non_negative())},
        {"prior", [&](const toml::node& pn, const std::string& pp) {
           const toml::table* pt = table(pn, pp);
           if (!pt) return false;
           for (auto&& [key, value] : *pt) {
             const std::string name(key.str());
             const std::optional<fsw::Effect> e = effect_from_name(name);
             if (!e) return fail(key, "unknown effect '" + pp + "." + name + "' (valid: " + effect_names() + ")");
             double v = 0.0;
             if (!read_number(value, pp + "." + name, positive(), v)) return false;
             c.diagnosis_prior[static_cast<std::size_t>(*e)] = v;
           }
           return true;
         }},
    });
  }
};

}  // namespace

FlightConfigResult parse_flight_config_text(const std::string& toml_text, const std::string& source_name,
                                            FlightConfig& cfg) {
  toml::table root;
  std::string error;
  if (!toml_schema::parse_document(toml_text, source_name, root, error)) return {false, error};
  FlightConfig c = cfg;
  Units u;
  Parser parser(source_name);
  if (!parser.file(root, c, u)) return {false, parser.error()};

  fsw::FlightAppConfig& a = c.app;
  fsw::ExecutiveConfig& x = a.exec;
  fsw::EkfConfig& e = a.exec.ekf;
  if (u.nav_rate_hz) x.nav_rate_hz = *u.nav_rate_hz;
  if (u.ekf_rate_hz) {
    // The one conversion of a rate into the whole navigation frames the executive counts.
    const double frames = x.nav_rate_hz / *u.ekf_rate_hz;
    if (std::abs(frames - std::round(frames)) > 1e-6 || std::round(frames) < 1.0) {
      return {false, source_name + ": 'executive.ekf_rate_hz' (" + toml_schema::format_number(*u.ekf_rate_hz) +
                         ") must divide 'executive.nav_rate_hz' (" + toml_schema::format_number(x.nav_rate_hz) +
                         ") into a whole number of navigation frames"};
    }
    x.frames_per_ekf = static_cast<int>(std::round(frames));
  }
  if (u.gnss_wait_s) x.gnss_wait_frames = static_cast<int>(std::lround(*u.gnss_wait_s * x.nav_rate_hz));
  // One value, two units: the datasheet's per sqrt(h) or SI per sqrt(s) (which states the paper's
  // values exactly), never both.
  for (const auto& [per_rthr, per_rts, rthr_key, rts_key] :
       {std::tuple{u.vrw_mps_per_rthr, u.vrw_mps_per_rts, "imu.vrw_mps_per_rthr", "imu.vrw_mps_per_rts"},
        std::tuple{u.arw_deg_per_rthr, u.arw_rad_per_rts, "imu.arw_deg_per_rthr", "imu.arw_rad_per_rts"}}) {
    if (per_rthr && per_rts)
      return {false, source_name + ": '" + rthr_key + "' and '" + rts_key + "' set the same value; give one of them"};
  }
  if (u.vrw_mps_per_rthr) e.vrw_mps_per_rts = alt_to_si(F::kVrw, *u.vrw_mps_per_rthr);
  if (u.arw_deg_per_rthr) e.arw_rad_per_rts = alt_to_si(F::kArw, *u.arw_deg_per_rthr);
  if (u.vrw_mps_per_rts) e.vrw_mps_per_rts = *u.vrw_mps_per_rts;
  if (u.arw_rad_per_rts) e.arw_rad_per_rts = *u.arw_rad_per_rts;
  if (u.clock_h0_s) e.clock_bias_psd_m2ps = to_si(F::kClockBiasPsd, *u.clock_h0_s);
  if (u.clock_h_minus2_per_s) e.clock_drift_psd_m2ps3 = to_si(F::kClockDriftPsd, *u.clock_h_minus2_per_s);
  if (u.accel_bias_sigma_mg) e.accel_bias_sigma_mps2 = to_si(F::kAccelBiasSigma, *u.accel_bias_sigma_mg);
  if (u.gyro_bias_sigma_degph) e.gyro_bias_sigma_radps = to_si(F::kGyroBiasSigma, *u.gyro_bias_sigma_degph);
  if (u.accel_scale_ppm) e.accel_scale_sigma = to_si(F::kAccelScaleSigma, *u.accel_scale_ppm);
  if (u.gyro_scale_ppm) e.gyro_scale_sigma = to_si(F::kGyroScaleSigma, *u.gyro_scale_ppm);
  if (u.accel_mis_arcsec) e.accel_misalign_sigma_rad = to_si(F::kAccelMisalignSigma, *u.accel_mis_arcsec);
  if (u.gyro_mis_arcsec) e.gyro_misalign_sigma_rad = to_si(F::kGyroMisalignSigma, *u.gyro_mis_arcsec);
  if (u.heading_offset_deg) a.init_heading_offset_rad = to_si(F::kInitHeadingOffset, *u.heading_offset_deg);
  if (u.roll_pitch_sigma_deg) {
    a.init_att_sigma_rad.x() = to_si(F::kInitRollSigma, *u.roll_pitch_sigma_deg);
    a.init_att_sigma_rad.y() = to_si(F::kInitPitchSigma, *u.roll_pitch_sigma_deg);
  }
  if (u.heading_sigma_deg) a.init_att_sigma_rad.z() = to_si(F::kInitHeadingSigma, *u.heading_sigma_deg);
  if (u.static_max_rate_dev_dps) a.static_max_rate_dev_radps = to_si(F::kStaticMaxRateDev, *u.static_max_rate_dev_dps);
  if (u.vm_max_heading_sigma_deg)
    a.vm_max_heading_sigma_rad = to_si(F::kVmMaxHeadingSigma, *u.vm_max_heading_sigma_deg);
  note_keys(root, "", source_name, c.key_file);
  c.files.push_back(source_name);
  cfg = std::move(c);
  return {true, ""};
}

FlightConfigResult parse_flight_config_file(const std::string& path, FlightConfig& cfg) {
  const std::optional<std::string> text = read_text_file(path);
  if (!text) return {false, path + ": cannot open flight configuration: " + text_file_problem(path)};
  return parse_flight_config_text(*text, path, cfg);
}

}  // namespace cfg
