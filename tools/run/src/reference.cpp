// The one reader of a log's reference (tools/reference.hpp).
#include "tools/reference.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "hal/lcm_channels.hpp"
#include "hal/lcm_convert.hpp"
#include "hal/lcm_log.hpp"

namespace tools {
namespace {

nlohmann::json sidecar_label(const std::string& path, std::string& source) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return nullptr;
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return nullptr;
  source = path;
  if (j.contains("reference") && j["reference"].is_object()) return j["reference"];
  if (j.value("format", std::string()) == "sdins-sim-sidecar")
    return {{"kind", "simulator_truth"}, {"source", "sdins sim"}, {"has_attitude", true}};
  return nullptr;
}

}  // namespace

Reference load_reference(const std::string& log_path) {
  Reference r;
  hal::LcmLogReader rd;
  if (rd.open(log_path) != hal::LcmLogStatus::kOk) throw std::runtime_error("cannot read " + log_path + ": " + rd.error());
  hal::LcmLogEvent ev;
  while (rd.next(ev) == hal::LcmLogStatus::kOk) {
    if (ev.channel != hal::kLcmChannelTruth) continue;
    ++r.messages;
    sdins::truth_t m{};
    if (hal::decode_exact(ev.data, ev.data_len, m) != hal::LcmInputStatus::kOk || !std::isfinite(m.t_s) ||
        (!r.samples.empty() && !(m.t_s > r.samples.back().t_s))) {
      ++r.rejected;
      continue;
    }
    ReferenceSample s;
    s.t_s = m.t_s;
    s.llh = fsw::Vec3(m.lat_rad, m.lon_rad, m.height_m);
    s.vel_enu_mps = fsw::Vec3(m.vel_enu_mps[0], m.vel_enu_mps[1], m.vel_enu_mps[2]);
    s.q_b_n = fsw::Quat(m.q_b_n_wxyz[0], m.q_b_n_wxyz[1], m.q_b_n_wxyz[2], m.q_b_n_wxyz[3]);
    s.has_position = s.llh.allFinite();
    s.has_velocity = s.vel_enu_mps.allFinite();
    const bool att_finite = s.q_b_n.coeffs().allFinite();
    s.has_attitude = att_finite && std::abs(s.q_b_n.norm() - 1.0) < 1e-3;
    s.attitude_not_unit = att_finite && !s.has_attitude;
    if (s.has_attitude)
      s.q_b_n.normalize();
    else
      s.q_b_n = fsw::Quat::Identity();
    if (!s.has_position && !s.has_velocity && !s.has_attitude) {
      ++r.rejected;
      continue;
    }
    r.samples.push_back(s);
  }
  r.label = sidecar_label(log_path + ".json", r.label_source);
  return r;
}

}  // namespace tools
