#include "tools/diagnosis_separation.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "sim/effects.hpp"
#include "sim/trajectory.hpp"
#include "tools/parallel.hpp"
#include "tools/number_text.hpp"

namespace tools {
namespace {

using sim::Segment;
using sim::SegmentType;
using sim::TurnDirection;

Segment straight(double duration_s) {
  Segment s;
  s.type = SegmentType::kStraight;
  s.duration_s = duration_s;
  return s;
}
Segment speed_change(double delta_mps, double duration_s) {
  Segment s;
  s.type = SegmentType::kSpeedChange;
  s.delta_speed_mps = delta_mps;
  s.duration_s = duration_s;
  return s;
}
Segment climb(double flight_path_deg, double hold_s, double transition_s) {
  Segment s;
  s.type = SegmentType::kClimb;
  s.flight_path_deg = flight_path_deg;
  s.duration_s = hold_s;
  s.transition_s = transition_s;
  return s;
}
Segment roll(TurnDirection d, double bank_deg, double hold_s, double roll_time_s) {
  Segment s;
  s.type = SegmentType::kRoll;
  s.direction = d;
  s.bank_deg = bank_deg;
  s.duration_s = hold_s;
  s.roll_time_s = roll_time_s;
  return s;
}
Segment turn(TurnDirection d, double bank_deg, double heading_change_deg, double roll_time_s) {
  Segment s;
  s.type = SegmentType::kTurn;
  s.direction = d;
  s.bank_deg = bank_deg;
  s.heading_change_deg = heading_change_deg;
  s.roll_time_s = roll_time_s;
  return s;
}
Segment crab(TurnDirection d, double crab_deg, double hold_s, double transition_s) {
  Segment s;
  s.type = SegmentType::kCrab;
  s.direction = d;
  s.crab_deg = crab_deg;
  s.duration_s = hold_s;
  s.transition_s = transition_s;
  return s;
}
TurnDirection other(TurnDirection d) { return d == TurnDirection::kRight ? TurnDirection::kLeft : TurnDirection::kRight; }

/// Crab angle of the candidate: 15 deg, the heading offset of a 65 m/s crosswind at 250 m/s.
constexpr double kCrabDeg = 15.0;

/// The candidates for a flight that ends at speed V after a turn of bank `bank_deg` to `last`.
std::vector<SeparationTrial> candidates_for(double V, TurnDirection last, double bank_deg) {
  // Speed changes of about 40 % and 50 % of the speed (rounded to 10 m/s, at least 10 m/s): what
  // tells a time offset (its error scales with the speed) from a lever arm along the velocity
  // takes a large one.
  const double dv = std::max(10.0, 10.0 * std::round(0.04 * V));
  const double half_v = std::max(10.0, 10.0 * std::round(0.05 * V));
  const double half_bank = std::max(5.0, 0.5 * bank_deg);
  std::vector<SeparationTrial> c(7);
  // Speed against time: the along-track error of a time offset grows with the speed, a lever
  // arm's does not; an accelerometer x scale factor sees the acceleration.
  c[0].label = "wings-level speed change";
  c[0].segments = {speed_change(dv, 30.0), straight(30.0), speed_change(-dv, 30.0), straight(30.0)};
  // Pitch rate and load factor without yaw rate.
  c[1].label = "pull-up and push-over";
  c[1].segments = {climb(10.0, 20.0, 10.0), climb(-10.0, 20.0, 10.0), straight(30.0)};
  // Bank held without turning: the load factor drops to cos(bank) and a lateral specific force
  // appears, with no body pitch or yaw rate (g-sensitivity apart from the rate-driven effects).
  c[2].label = "roll without turning";
  c[2].segments = {roll(TurnDirection::kRight, 45.0, 60.0, 5.0), roll(TurnDirection::kLeft, 45.0, 60.0, 5.0),
                   straight(30.0)};
  // Another ratio of body pitch rate to yaw rate (sin against cos of the bank) and load factor.
  c[3].label = "turns at half the bank";
  c[3].segments = {turn(other(last), half_bank, 90.0, 5.0), straight(30.0), turn(last, half_bank, 90.0, 5.0),
                   straight(30.0)};
  // The same bank at half the speed: the turn rate (g tan(bank) / V) doubles, the load factor does
  // not, and the lever arm a time offset looks like (speed x offset) halves.
  c[4].label = "turns at half the speed";
  c[4].segments = {speed_change(-half_v, 40.0), turn(other(last), bank_deg, 180.0, 5.0), turn(last, bank_deg, 180.0, 5.0),
                   speed_change(half_v, 40.0), straight(30.0)};
  // Heading coverage: a whole turn, to the side the flight turned last from.
  c[5].label = "a full turn the other way";
  c[5].segments = {turn(other(last), bank_deg, 360.0, 5.0), straight(30.0)};
  // The nose off the track, both ways, wings level with the velocity unchanged (a crosswind crab):
  // the body x axis leaves the velocity, so a lever arm along x moves the antenna across the track
  // while a time offset's error stays along it; every other segment keeps body x on the velocity.
  c[6].label = "crab both ways";
  c[6].segments = {crab(TurnDirection::kRight, kCrabDeg, 60.0, 10.0), crab(TurnDirection::kLeft, kCrabDeg, 60.0, 10.0),
                   straight(30.0)};
  return c;
}

/// A trial under evaluation: which candidates it combines.
struct Trial {
  SeparationTrial t;
  std::vector<int> parts;  ///< indices into the single candidates
};

/// Candidate indices of the group's members.
std::vector<int> member_candidates(const Finding& f) {
  const std::vector<Candidate>& cands = diagnosis_candidates();
  std::vector<int> out;
  for (const GroupMember& m : f.group)
    for (std::size_t c = 0; c < cands.size(); ++c)
      if (candidate_name(cands[c]) == m.name) out.push_back(static_cast<int>(c));
  return out;
}

/// Positions of the candidates in a run's active list (-1 where absent).
std::vector<int> positions(const DiagnosisRun& run, const std::vector<int>& members) {
  std::vector<int> pos;
  for (int c : members) {
    const auto it = std::find(run.active.begin(), run.active.end(), c);
    pos.push_back(it == run.active.end() ? -1 : static_cast<int>(it - run.active.begin()));
  }
  return pos;
}


}  // namespace

double group_correlation(const Eigen::MatrixXd& R, const std::vector<int>& pos, std::vector<double>* per_member) {
  double worst = 0.0;
  if (per_member) per_member->assign(pos.size(), 0.0);
  for (std::size_t i = 0; i < pos.size(); ++i) {
    std::vector<int> others;
    for (std::size_t j = 0; j < pos.size(); ++j)
      if (j != i) others.push_back(pos[j]);
    const double m = multiple_correlation(R, pos[i], others);
    if (per_member) (*per_member)[i] = m;
    worst = std::max(worst, m);
  }
  return worst;
}

std::vector<SeparationTrial> separation_candidates(const sim::Scenario& flown) {
  sim::FlownSegments fs;
  std::string err;
  double V = flown.start.speed_mps;
  TurnDirection last = TurnDirection::kLeft;
  double bank = 60.0;
  if (sim::flown_segments(flown, fs, err)) {
    for (const Segment& s : fs.segments) {
      if (s.type == SegmentType::kSpeedChange) V += s.delta_speed_mps;
      if (s.type == SegmentType::kTurn) {
        last = s.direction;
        bank = s.bank_deg;
      }
    }
  }
  return candidates_for(V, last, bank);
}

std::vector<SeparationTrial> separation_candidates() {
  const sim::Scenario def;
  return candidates_for(def.start.speed_mps, TurnDirection::kLeft, 60.0);
}

FlownScenario scenario_from_sidecar(const std::string& log_path) {
  FlownScenario out;
  namespace fs = std::filesystem;
  const std::string sidecar = log_path + ".json";
  std::error_code ec;
  if (!fs::is_regular_file(sidecar, ec)) {
    out.note = "no scenario is known for this recording (no simulator sidecar " + sidecar +
               "): a measured recording; the segments are suggested without a prediction";
    return out;
  }
  try {
    std::ifstream in(sidecar);
    const nlohmann::json j = nlohmann::json::parse(in);
    if (j.value("format", "") == "sdins-import-summary") {  // `sdins import` writes its summary there
      out.note = "no scenario is known for this recording (" + sidecar +
                 " is its import summary): a measured recording; the segments are suggested without a prediction";
      return out;
    }
    if (j.value("format", "") != "sdins-sim-sidecar") {
      out.note = sidecar + " is not an sdins sim sidecar: no scenario is known, segments without a prediction";
      return out;
    }
    sim::Scenario sc;
    const std::string file = j.at("scenario_file").get<std::string>();
    std::string scenario_text = "the built-in scenario";
    if (!file.empty()) {
      fs::path p(file);
      if (p.is_relative() && !fs::exists(p, ec)) p = fs::path(log_path).parent_path() / file;
      const sim::ScenarioParseResult pr = sim::parse_scenario_file(p.string());
      if (!pr.ok()) {
        out.note = "the scenario named by " + sidecar + " cannot be read (" + pr.error +
                   "): segments without a prediction";
        return out;
      }
      sc = *pr.scenario;
      scenario_text = "scenario file " + p.string();
    }
    sc.seed = j.at("seed").get<std::uint64_t>();
    sc.duration_s = j.at("duration_s").get<double>();
    const std::string errors = j.at("truth_errors").get<std::string>();
    if (errors == "paper") sc.imu.errors = sim::ImuErrorSet::kPaper;
    else if (errors == "baseline") sc.imu.errors = sim::ImuErrorSet::kBaseline;
    else if (errors == "none") sc.imu.errors = sim::ImuErrorSet::kNone;
    else throw std::runtime_error("unknown truth_errors '" + errors + "'");
    sc.effects = sim::EffectSet{};
    for (const nlohmann::json& e : j.at("effects")) {
      const std::string name = e.at("name").get<std::string>();
      const std::optional<fsw::Effect> eff = sim::effect_from_name(name);
      if (!eff) throw std::runtime_error("unknown effect '" + name + "'");
      const std::optional<std::size_t> k = sim::component_from_name(*eff, e.at("component").get<std::string>());
      if (!k) throw std::runtime_error("unknown component of '" + name + "'");
      sc.effects.set(*eff, *k, e.at("value").get<double>());
    }
    if (j.at("imu_rate_hz").get<int>() != sc.imu.rate_hz || j.at("gps_rate_hz").get<double>() != sc.gps.rate_hz) {
      out.note = "the scenario named by " + sidecar + " no longer matches the log (IMU or GPS rate): segments "
                 "without a prediction";
      return out;
    }
    out.known = true;
    out.scenario = sc;
    out.source = "sidecar " + sidecar + ": " + scenario_text + ", seed " + std::to_string(sc.seed) + ", " +
                 fmt("%g", sc.duration_s) + " s";
  } catch (const std::exception& e) {
    out.known = false;
    out.note = "the sidecar " + sidecar + " cannot be read (" + e.what() + "): segments without a prediction";
  }
  return out;
}

namespace {

/// What every step of suggest_separations shares: the diagnosis, the flight flown, the groups
/// (indices into r.findings) and each group's member candidates.
struct SeparationContext {
  const DiagnosisResult& r;
  const DiagnosisConfig& cfg;
  const FlownScenario& flown;
  std::size_t nf = 0;                      ///< findings
  std::vector<std::vector<int>> members;   ///< per finding: its group's member candidates
  std::vector<std::size_t> groups;         ///< the findings that are groups
};

/// The groups among the findings, each with its members and their correlation as flown.
void collect_groups(SeparationContext& ctx, std::vector<Separation>& out) {
  for (std::size_t i = 0; i < ctx.nf; ++i) {
    const Finding& f = ctx.r.findings[i];
    if (f.separable()) continue;
    Separation& s = out[i];
    for (const GroupMember& m : f.group) s.members.push_back(m.name);
    s.max_correlation = ctx.cfg.max_correlation;
    ctx.members[i] = member_candidates(f);
    const std::vector<int> pos = positions(ctx.r.extended, ctx.members[i]);
    if (ctx.r.extended.initialised && std::find(pos.begin(), pos.end(), -1) == pos.end())
      s.flown_correlation = group_correlation(ctx.r.extended.correlation, pos);
    ctx.groups.push_back(i);
  }
}

/// Segments only: every candidate, one after the other (a test flight that flies them all).
void segments_without_prediction(const std::vector<std::size_t>& groups, const std::string& why_not,
                                 std::vector<Separation>& out) {
  const std::vector<SeparationTrial> cands = separation_candidates();
  for (std::size_t i : groups) {
    Separation& s = out[i];
    s.predicted = false;
    s.note = why_not;
    s.label = "every candidate manoeuvre in turn (not predicted)";
    for (const SeparationTrial& c : cands) {
      s.label += (s.segments.empty() ? ": " : ", ") + c.label;
      s.segments.insert(s.segments.end(), c.segments.begin(), c.segments.end());
    }
    s.segments_toml = sim::segments_toml(s.segments);
  }
}

/// One trial: the flown scenario with the trial's segments appended, simulated, and the extended
/// model run over it; the predicted correlation of each group's members.
void evaluate_trial(const SeparationContext& ctx, Trial& tr) {
  SeparationTrial& t = tr.t;
  try {
    sim::Scenario ext;
    std::string err;
    if (!sim::append_segments(ctx.flown.scenario, t.segments, ext, err)) {
      t.error = err;
      return;
    }
    t.added_s = ext.duration_s - ctx.flown.scenario.duration_s;
    // The covariance depends on the trajectory, not on how finely the IMU samples it: the
    // prediction flies the IMU at the navigation rate when the scenario's is a multiple of it.
    if (ext.imu.rate_hz > kPredictionImuRate_hz && ext.imu.rate_hz % kPredictionImuRate_hz == 0)
      ext.imu.rate_hz = kPredictionImuRate_hz;
    const RecordedData d = record_scenario(ext, ext.seed);
    const DiagnosisRun run = run_diagnosis_model(d, ctx.cfg, ctx.r.extended.active);
    if (!run.initialised) {
      t.error = "the diagnosis model did not initialise on the simulated flight";
      return;
    }
    t.correlation.assign(ctx.nf, NAN);
    t.member_correlation.assign(ctx.nf, {});
    t.member_sigma.assign(ctx.nf, {});
    for (std::size_t i : ctx.groups) {
      const std::vector<int> pos = positions(run, ctx.members[i]);
      if (std::find(pos.begin(), pos.end(), -1) != pos.end()) continue;
      t.correlation[i] = group_correlation(run.correlation, pos, &t.member_correlation[i]);
      for (int p : pos) t.member_sigma[i].push_back(run.sigma[static_cast<std::size_t>(p)]);
    }
    t.evaluated = true;
  } catch (const std::exception& e) {
    t.error = e.what();
  }
}

/// The trials evaluated on the hardware's threads.
void evaluate_all(const SeparationContext& ctx, std::vector<Trial>& trials) {
  for_each_parallel(trials.size(), [&](std::size_t k) { evaluate_trial(ctx, trials[k]); });
}

/// Group g's trial with the lowest predicted correlation (index into all), -1 if none was evaluated.
int best_of(const std::vector<Trial>& all, std::size_t g) {
  int best = -1;
  for (std::size_t k = 0; k < all.size(); ++k) {
    const SeparationTrial& t = all[k].t;
    if (!t.evaluated || !std::isfinite(t.correlation[g])) continue;
    if (best < 0 || t.correlation[g] < all[static_cast<std::size_t>(best)].t.correlation[g]) best = static_cast<int>(k);
  }
  return best;
}

/// Whether a trial of the same parts (in any order) is among the trials.
bool has_parts(const std::vector<Trial>& trials, const std::vector<int>& key) {
  bool seen = false;
  for (const Trial& x : trials) {
    std::vector<int> xk = x.parts;
    std::sort(xk.begin(), xk.end());
    seen = seen || xk == key;
  }
  return seen;
}

/// The combinations of `round` parts to try: for each group not yet separated whose best is of the
/// last round, the best so far followed by one of the kCombineBest best single candidates for this
/// group (the same one again too: more of what informs), each sequence once.
std::vector<Trial> combinations(const SeparationContext& ctx, const std::vector<SeparationTrial>& singles,
                                const std::vector<Trial>& all, int round) {
  std::vector<Trial> more;
  for (std::size_t g : ctx.groups) {
    const int b = best_of(all, g);
    if (b < 0 || all[static_cast<std::size_t>(b)].t.correlation[g] < ctx.cfg.max_correlation) continue;
    const Trial base = all[static_cast<std::size_t>(b)];
    if (static_cast<int>(base.parts.size()) != round - 1) continue;  // the best is not of the last round
    std::vector<std::size_t> rank;
    for (std::size_t k = 0; k < singles.size(); ++k)
      if (all[k].t.evaluated && std::isfinite(all[k].t.correlation[g])) rank.push_back(k);
    std::sort(rank.begin(), rank.end(),
              [&](std::size_t a, std::size_t b2) { return all[a].t.correlation[g] < all[b2].t.correlation[g]; });
    if (rank.size() > static_cast<std::size_t>(kCombineBest)) rank.resize(static_cast<std::size_t>(kCombineBest));
    for (std::size_t k : rank) {
      Trial t;
      t.parts = base.parts;
      t.parts.push_back(static_cast<int>(k));
      std::vector<int> key = t.parts;
      std::sort(key.begin(), key.end());
      if (has_parts(all, key) || has_parts(more, key)) continue;
      t.t.label = base.t.label + " + " + singles[k].label;
      t.t.segments = base.t.segments;
      t.t.segments.insert(t.t.segments.end(), singles[k].segments.begin(), singles[k].segments.end());
      more.push_back(t);
    }
  }
  return more;
}

/// Group g's separation from its best trial (all.size() trials evaluated), with the whole scenario
/// to fly as TOML.
void set_separation(const SeparationContext& ctx, const std::vector<Trial>& all, std::size_t g, Separation& s) {
  const int b = best_of(all, g);
  if (b < 0) {
    s.note = "no candidate could be evaluated";
    for (const Trial& t : all)
      if (!t.t.error.empty()) {
        s.note += ": " + t.t.error;
        break;
      }
    return;
  }
  const FlownScenario& flown = ctx.flown;
  const SeparationTrial& t = all[static_cast<std::size_t>(b)].t;
  s.predicted = true;
  s.label = t.label;
  s.segments = t.segments;
  s.segments_toml = sim::segments_toml(t.segments);
  s.added_s = t.added_s;
  s.predicted_correlation = t.correlation[g];
  s.member_correlation = t.member_correlation[g];
  s.member_sigma = t.member_sigma[g];
  s.separates = s.predicted_correlation < ctx.cfg.max_correlation;
  s.note = "predicted by the extended model over the flown scenario (" + flown.source + ") with " +
           std::to_string(all.size()) + " candidate segment sequences appended, simulated";
  sim::Scenario ext;
  std::string err;
  if (sim::append_segments(flown.scenario, t.segments, ext, err)) {
    std::string group;
    for (const std::string& m : s.members) group += (group.empty() ? "" : ", ") + m;
    ext.name = flown.scenario.name + " + " + t.label;
    const sim::ScenarioWriteResult w = sim::write_scenario_toml(
        ext, "The flown scenario (" + flown.source + ")\nwith the segments that separate " + group +
                 " appended\n(" + t.label + ", from t = " + fmt("%g", flown.scenario.duration_s) + " s; written by "
                 "sdins diagnose, docs/diagnosis-separation.md).\nPredicted correlation of the members " +
                 fmt("%.3f", s.predicted_correlation) + " (flown: " + fmt("%.4f", s.flown_correlation) + ").");
    if (w.ok()) s.scenario_toml = w.text;
    else s.note += "; the scenario file cannot be written: " + w.error;
  } else {
    s.note += "; " + err;
  }
}

}  // namespace

std::vector<Separation> suggest_separations(const DiagnosisResult& r, const DiagnosisConfig& cfg,
                                            const FlownScenario& flown,
                                            const std::function<void(const std::string&)>& progress,
                                            std::vector<SeparationTrial>* trials_out) {
  auto say = [&progress](const std::string& s) {
    if (progress) progress(s);
  };
  SeparationContext ctx{r, cfg, flown, r.findings.size(), std::vector<std::vector<int>>(r.findings.size()), {}};
  std::vector<Separation> out(ctx.nf);
  collect_groups(ctx, out);
  if (ctx.groups.empty()) return out;

  std::string why_not;
  if (!flown.known) why_not = flown.note;
  else if (cfg.gnss_source != cfg::GnssSource::kRaw)
    why_not = "the diagnosis took GNSS solutions, which the simulator does not make: segments without a prediction";
  if (!why_not.empty()) {
    segments_without_prediction(ctx.groups, why_not, out);
    return out;
  }

  std::vector<SeparationTrial> singles = separation_candidates(flown.scenario);
  std::vector<Trial> all;
  for (std::size_t k = 0; k < singles.size(); ++k) all.push_back(Trial{singles[k], {static_cast<int>(k)}});
  say("separation: " + std::to_string(all.size()) + " candidate manoeuvres appended to the flown flight, the "
      "extended model over each");
  evaluate_all(ctx, all);
  for (int round = 2; round <= kMaxCombined; ++round) {
    std::vector<Trial> more = combinations(ctx, singles, all, round);
    if (more.empty()) break;
    say("separation: no single manoeuvre separates every group; " + std::to_string(more.size()) +
        " combinations of " + std::to_string(round));
    evaluate_all(ctx, more);
    all.insert(all.end(), more.begin(), more.end());
  }
  for (std::size_t g : ctx.groups) set_separation(ctx, all, g, out[g]);
  if (trials_out) {
    trials_out->clear();
    for (const Trial& t : all) trials_out->push_back(t.t);
  }
  return out;
}

}  // namespace tools
