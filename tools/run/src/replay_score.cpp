// Scoring a replay against the log's reference (tools/replay_score.hpp).
#include "tools/replay_score.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "fsw/frames.hpp"
#include "hal/lcm_channels.hpp"

namespace tools {
namespace {

constexpr double kChi2_3_95 = 7.8147;  ///< 95% point of the chi-square distribution with 3 dof

double wrap_deg(double d) {
  d = std::fmod(d + 180.0, 360.0);
  if (d < 0) d += 360.0;
  return d - 180.0;
}

}  // namespace

void RmsMax::add(double x) {
  ++n;
  sum2 += x * x;
  max = std::max(max, std::abs(x));
}

double RmsMax::rms() const { return n > 0 ? std::sqrt(sum2 / static_cast<double>(n)) : 0.0; }

nlohmann::json RmsMax::to_json(const char* unit) const {
  if (n == 0) return nullptr;
  return {{std::string("rms_") + unit, rms()}, {std::string("max_") + unit, max}, {"samples", n}};
}

ReplayScorer::ReplayScorer(Reference ref, const ScoreOptions& opt) : ref_(std::move(ref)), opt_(opt) {}

bool ReplayScorer::errors_at(const fsw::NavState& nav, Errors& e) const {
  const auto& s = ref_.samples;
  const auto it = std::lower_bound(s.begin(), s.end(), nav.t_s, [](const ReferenceSample& a, double t) { return a.t_s < t; });
  if (it == s.end()) return false;
  const std::size_t j = static_cast<std::size_t>(it - s.begin());
  const ReferenceSample& b = s[j];
  const bool exact = b.t_s == nav.t_s;
  if (!exact && (j == 0 || b.t_s - s[j - 1].t_s > opt_.max_reference_gap_s)) return false;
  const ReferenceSample& a = exact ? b : s[j - 1];
  const double w = exact ? 1.0 : (nav.t_s - a.t_s) / (b.t_s - a.t_s);
  if (a.has_position && b.has_position) {
    e.pos = true;
    e.dpos = fsw::enu_difference_m(nav.llh, (1.0 - w) * a.llh + w * b.llh);
  }
  if (a.has_velocity && b.has_velocity) {
    e.vel = true;
    e.dvel = nav.vel_enu_mps - ((1.0 - w) * a.vel_enu_mps + w * b.vel_enu_mps);
  }
  if (a.has_attitude && b.has_attitude) {
    e.att = true;
    const fsw::Vec3 en = fsw::euler_from_C_b_n(nav.C_b_n());
    const fsw::Vec3 er = fsw::euler_from_C_b_n(a.q_b_n.slerp(w, b.q_b_n).toRotationMatrix());
    for (int i = 0; i < 3; ++i) e.datt_deg[i] = wrap_deg((en[i] - er[i]) * fsw::kRadToDeg);
  }
  return e.pos || e.vel || e.att;
}

ReplayScorer::Window* ReplayScorer::window_at(double t_s, double init_t_s, double& since_start) {
  if (!(opt_.outage_length_s > 0.0) || !(opt_.outage_period_s > 0.0)) return nullptr;
  const double t0 = init_t_s + opt_.outage_first_s;
  if (t_s < t0) return nullptr;
  const int k = static_cast<int>(std::floor((t_s - t0) / opt_.outage_period_s));
  // Windows before this one are over: the data went past their end.
  for (Window& w : windows_)
    if (w.index < k || t_s >= w.end_s) w.complete = true;
  since_start = t_s - t0 - k * opt_.outage_period_s;
  if (since_start >= opt_.outage_length_s) return nullptr;
  if (windows_.empty() || windows_.back().index != k) {
    Window w;
    w.index = k;
    w.start_s = t0 + k * opt_.outage_period_s;
    w.end_s = w.start_s + opt_.outage_length_s;
    windows_.push_back(w);
  }
  return &windows_.back();
}

void ReplayScorer::on_frame(const fsw::NavState& nav, double init_t_s) {
  ++frames_;
  if (frames_ == 1) first_t_ = nav.t_s;
  last_t_ = nav.t_s;
  init_t_ = init_t_s;
  double since = 0.0;
  Window* w = window_at(nav.t_s, init_t_s, since);
  if (nav.t_s < init_t_s + opt_.from_s) {
    ++before_from_;
    return;
  }
  Errors e;
  if (!errors_at(nav, e)) {
    ++without_reference_;
    return;
  }
  ++scored_;
  if (e.pos) {
    h_.add(std::hypot(e.dpos.x(), e.dpos.y()));
    v_.add(e.dpos.z());
  }
  if (e.vel) {
    vel_.add(e.dvel.norm());
    vel_h_.add(std::hypot(e.dvel.x(), e.dvel.y()));
    vel_v_.add(e.dvel.z());
  }
  if (e.att) {
    roll_.add(e.datt_deg.x());
    pitch_.add(e.datt_deg.y());
    heading_.add(e.datt_deg.z());
  }
  if (w != nullptr && e.pos) {
    const double hh = std::hypot(e.dpos.x(), e.dpos.y());
    w->has_end = true;
    w->end_h_m = hh;
    w->end_v_m = e.dpos.z();
    w->end_t_s = since;
    if (since >= w->next_curve_s) {
      w->curve.push_back({since, hh, e.dpos.z()});
      w->next_curve_s = (std::floor(since / opt_.curve_step_s) + 1.0) * opt_.curve_step_s;
    }
  }
  if (nav.t_s >= next_row_t_) {
    rows_.push_back({nav.t_s, nav.t_s - init_t_s, w != nullptr ? w->index : -1, w != nullptr ? since : NAN, e});
    next_row_t_ = nav.t_s + opt_.csv_step_s - 1e-9;
  }
}

void ReplayScorer::on_ekf(const fsw::NavState& nav, double init_t_s, const std::array<double, 6>& sigma) {
  if (nav.t_s < init_t_s + opt_.from_s) return;
  Errors e;
  if (!errors_at(nav, e) || !e.pos || !e.vel) return;
  double np = 0.0, nv = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double sp = sigma[static_cast<std::size_t>(i)], sv = sigma[static_cast<std::size_t>(i + 3)];
    if (!(sp > 0.0) || !(sv > 0.0)) return;
    np += std::pow(e.dpos[i] / sp, 2);
    nv += std::pow(e.dvel[i] / sv, 2);
  }
  ++nees_n_;
  nees_pos_sum_ += np;
  nees_vel_sum_ += nv;
  nees_pos_over_ += np > kChi2_3_95 ? 1 : 0;
  nees_vel_over_ += nv > kChi2_3_95 ? 1 : 0;
  double since = 0.0;
  Window* w = window_at(nav.t_s, init_t_s, since);
  if (w != nullptr) {
    w->end_nees_h = std::pow(e.dpos.x() / sigma[0], 2) + std::pow(e.dpos.y() / sigma[1], 2);
    w->end_sigma_h_m = std::hypot(sigma[0], sigma[1]);
  }
}

nlohmann::json ReplayScorer::result() const {
  nlohmann::json j;
  std::uint64_t wp = 0, wv = 0, wa = 0;
  for (const ReferenceSample& s : ref_.samples) {
    wp += s.has_position ? 1 : 0;
    wv += s.has_velocity ? 1 : 0;
    wa += s.has_attitude ? 1 : 0;
  }
  j["reference"] = {{"channel", hal::kLcmChannelTruth},
                    {"samples", ref_.samples.size()},
                    {"with_position", wp},
                    {"with_velocity", wv},
                    {"with_attitude", wa},
                    {"rejected", ref_.rejected},
                    {"label", ref_.label},
                    {"label_source", ref_.label_source}};
  j["from_s_after_init"] = opt_.from_s;
  j["max_reference_gap_s"] = opt_.max_reference_gap_s;
  j["frames"] = {{"total", frames_}, {"scored", scored_}, {"without_reference", without_reference_}, {"before_from", before_from_}};
  j["position"] = {{"horizontal", h_.to_json("m")}, {"vertical", v_.to_json("m")}};
  j["velocity"] = {{"norm", vel_.to_json("mps")}, {"horizontal", vel_h_.to_json("mps")}, {"vertical", vel_v_.to_json("mps")}};
  j["attitude"] = {{"roll", roll_.to_json("deg")}, {"pitch", pitch_.to_json("deg")}, {"heading", heading_.to_json("deg")}};
  const double n = static_cast<double>(nees_n_);
  j["nees"] = nees_n_ == 0 ? nlohmann::json(nullptr)
                           : nlohmann::json{{"epochs", nees_n_},
                                            {"dof", 3},
                                            {"position_mean", nees_pos_sum_ / n},
                                            {"velocity_mean", nees_vel_sum_ / n},
                                            {"position_above_95pct_fraction", static_cast<double>(nees_pos_over_) / n},
                                            {"velocity_above_95pct_fraction", static_cast<double>(nees_vel_over_) / n},
                                            {"sigma", "EKF_STATE 1-sigma (diagonal) at each EKF run"},
                                            {"caveat", kReferenceNeesCaveat}};
  if (opt_.outage_length_s > 0.0) {
    nlohmann::json ws = nlohmann::json::array();
    RmsMax eh, ev, sh;
    double nees_sum = 0.0;
    std::uint64_t nees_n = 0;
    for (const Window& w : windows_) {
      nlohmann::json curve = nlohmann::json::array();
      for (const auto& c : w.curve) curve.push_back({c[0], c[1], c[2]});
      if (w.has_end && (w.curve.empty() || w.curve.back()[0] < w.end_t_s)) curve.push_back({w.end_t_s, w.end_h_m, w.end_v_m});
      const bool complete = w.complete && w.has_end;
      ws.push_back({{"index", w.index},
                    {"start_t_s", w.start_s},
                    {"end_t_s", w.end_s},
                    {"complete", complete},
                    {"end_horizontal_m", w.has_end ? nlohmann::json(w.end_h_m) : nlohmann::json(nullptr)},
                    {"end_vertical_m", w.has_end ? nlohmann::json(w.end_v_m) : nlohmann::json(nullptr)},
                    {"end_since_start_s", w.has_end ? nlohmann::json(w.end_t_s) : nlohmann::json(nullptr)},
                    {"end_horizontal_nees", w.end_nees_h >= 0 ? nlohmann::json(w.end_nees_h) : nlohmann::json(nullptr)},
                    {"end_horizontal_sigma_m", w.end_sigma_h_m >= 0 ? nlohmann::json(w.end_sigma_h_m) : nlohmann::json(nullptr)},
                    {"curve", curve}});
      if (!complete) continue;
      eh.add(w.end_h_m);
      ev.add(w.end_v_m);
      if (w.end_nees_h >= 0) {
        nees_sum += w.end_nees_h;
        ++nees_n;
        sh.add(w.end_sigma_h_m);
      }
    }
    j["outages"] = {{"length_s", opt_.outage_length_s},
                    {"period_s", opt_.outage_period_s},
                    {"first_s_after_init", opt_.outage_first_s},
                    {"windows", ws},
                    {"complete", eh.n},
                    {"end_horizontal", eh.to_json("m")},
                    {"end_vertical", ev.to_json("m")},
                    {"end_horizontal_nees_mean", nees_n > 0 ? nlohmann::json(nees_sum / static_cast<double>(nees_n)) : nlohmann::json(nullptr)},
                    {"end_horizontal_sigma", sh.to_json("m")},
                    {"curve", "[time since the outage began s, horizontal m, vertical m] every " +
                                  std::to_string(opt_.curve_step_s) + " s (the first frame at or after each step)"}};
  }
  j["errors"] = "solution minus reference: position ENU (horizontal |E,N|, vertical U), velocity ENU, roll/pitch/heading";
  return j;
}

std::string ReplayScorer::csv() const {
  std::ostringstream o;
  o.precision(10);
  o << "t_s,since_init_s,outage,since_outage_start_s,pos_e_m,pos_n_m,pos_u_m,horizontal_m,vel_e_mps,vel_n_mps,vel_u_mps,"
       "roll_deg,pitch_deg,heading_deg\n";
  const auto cell = [&](bool ok, double v) {
    if (ok) o << v;
    o << ',';
  };
  for (const Row& r : rows_) {
    o << r.t_s << ',' << r.since_init_s << ',' << r.outage << ',';
    cell(r.outage >= 0, r.since_outage_s);
    for (int i = 0; i < 3; ++i) cell(r.e.pos, r.e.dpos[i]);
    cell(r.e.pos, std::hypot(r.e.dpos.x(), r.e.dpos.y()));
    for (int i = 0; i < 3; ++i) cell(r.e.vel, r.e.dvel[i]);
    for (int i = 0; i < 3; ++i) {
      if (r.e.att) o << r.e.datt_deg[i];
      if (i < 2) o << ',';
    }
    o << '\n';
  }
  return o.str();
}

namespace {
std::string f3(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.3f", v);
  return b;
}
std::string rms_max(const nlohmann::json& j, const char* unit) {
  if (j.is_null()) return "no reference";
  return "RMS " + f3(j[std::string("rms_") + unit].get<double>()) + " (max " + f3(j[std::string("max_") + unit].get<double>()) + ")";
}
}  // namespace

std::string ReplayScorer::text(const nlohmann::json& s) {
  std::ostringstream o;
  const auto& r = s["reference"];
  o << "score against " << r["channel"].get<std::string>() << ": " << r["samples"].get<std::uint64_t>() << " reference samples ("
    << r["with_position"].get<std::uint64_t>() << " position, " << r["with_velocity"].get<std::uint64_t>() << " velocity, "
    << r["with_attitude"].get<std::uint64_t>() << " attitude; " << r["rejected"].get<std::uint64_t>() << " rejected); reference: ";
  if (r["label"].is_null())
    o << "unlabelled (no LOG.json with a \"reference\" beside the log)";
  else
    o << r["label"].value("kind", std::string("?")) << " from " << r["label"].value("source", std::string("?"));
  const auto& fr = s["frames"];
  o << "\n  frames from init + " << f3(s["from_s_after_init"].get<double>()) << " s: " << fr["scored"].get<std::uint64_t>()
    << " scored, " << fr["without_reference"].get<std::uint64_t>() << " without reference within "
    << f3(s["max_reference_gap_s"].get<double>()) << " s\n";
  o << "  position [m]:   horizontal " << rms_max(s["position"]["horizontal"], "m") << ", vertical "
    << rms_max(s["position"]["vertical"], "m") << "\n";
  o << "  velocity [m/s]: " << rms_max(s["velocity"]["norm"], "mps") << " (horizontal " << rms_max(s["velocity"]["horizontal"], "mps")
    << ", vertical " << rms_max(s["velocity"]["vertical"], "mps") << ")\n";
  o << "  attitude [deg]: roll " << rms_max(s["attitude"]["roll"], "deg") << ", pitch " << rms_max(s["attitude"]["pitch"], "deg")
    << ", heading " << rms_max(s["attitude"]["heading"], "deg") << "\n";
  if (!s["nees"].is_null()) {
    const auto& n = s["nees"];
    o << "  NEES (3 if consistent, " << n["epochs"].get<std::uint64_t>() << " EKF runs): position " << f3(n["position_mean"].get<double>())
      << " (" << f3(100.0 * n["position_above_95pct_fraction"].get<double>()) << "% above the 95% point), velocity "
      << f3(n["velocity_mean"].get<double>()) << " (" << f3(100.0 * n["velocity_above_95pct_fraction"].get<double>()) << "%)\n"
      << "  caveat: " << kReferenceNeesCaveat << "\n";
  }
  if (s.contains("outages")) {
    const auto& g = s["outages"];
    o << "  outages: " << g["complete"].get<std::uint64_t>() << " complete of " << g["windows"].size()
      << "; at their end: horizontal " << rms_max(g["end_horizontal"], "m") << " m, vertical " << rms_max(g["end_vertical"], "m")
      << " m";
    if (!g["end_horizontal_nees_mean"].is_null())
      o << "; the filter's horizontal 1-sigma there RMS " << f3(g["end_horizontal_sigma"]["rms_m"].get<double>())
        << " m, horizontal NEES " << f3(g["end_horizontal_nees_mean"].get<double>()) << " (2 if consistent)";
    o << "\n";
    for (const auto& w : g["windows"]) {
      o << "    outage " << w["index"].get<int>() << " at t_s " << f3(w["start_t_s"].get<double>()) << ": ";
      if (w["end_horizontal_m"].is_null()) {
        o << "no reference in it\n";
        continue;
      }
      o << "after " << f3(w["end_since_start_s"].get<double>()) << " s horizontal " << f3(w["end_horizontal_m"].get<double>())
        << " m, vertical " << f3(w["end_vertical_m"].get<double>()) << " m";
      if (!w["end_horizontal_sigma_m"].is_null())
        o << " (filter 1-sigma " << f3(w["end_horizontal_sigma_m"].get<double>()) << " m)";
      if (!w["complete"].get<bool>()) o << " (incomplete: the log ends in it)";
      o << "\n";
    }
  }
  return o.str();
}

}  // namespace tools
