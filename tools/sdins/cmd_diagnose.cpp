// sdins diagnose: which error the navigation model is missing in a recording, how large it is,
// and how much better navigation gets with it (tools/diagnosis.hpp, docs/diagnosis.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "commands.hpp"
#include "tools/interrupt.hpp"
#include "tools/output_file.hpp"
#include "tools/diagnosis.hpp"
#include "tools/fsw_report.hpp"
#include "cfg/flight_config.hpp"
#include "tools/diagnosis_chain.hpp"
#include "tools/diagnosis_evidence.hpp"
#include "tools/diagnosis_intervals.hpp"
#include "tools/diagnosis_separation.hpp"
#include "tools/number_text.hpp"
#include <chrono>

namespace sdins {
namespace {
using tools::fmt;

struct DiagnoseOptions {
  std::string log;
  std::string json;
  std::string report;
  std::string baseline = "15";
  double alpha = 0.05;
  std::string flight_config;
  std::string intervals = "profile";
  std::vector<std::string> profile;
  bool profile_only = false;
  bool no_chain = false;
} diagnose_opt;

nlohmann::json innovations_json(const tools::InnovationStats& s) {
  return {{"epochs", s.epochs},
          {"pseudorange_used", s.pr_used},
          {"pseudorange_rate_used", s.prr_used},
          {"gated", s.rejected},
          {"nis_mean", s.nis_mean},
          {"position_used", s.pos_used},
          {"velocity_used", s.vel_used},
          {"innovation_rms",
           {{"pseudorange_m", s.pr_rms_m},
            {"pseudorange_rate_mps", s.prr_rms_mps},
            {"position_m", s.pos_rms_m},
            {"velocity_mps", s.vel_rms_mps}}},
          {"log_likelihood", s.log_likelihood},
          {"log_likelihood_measurements", s.common}};
}

nlohmann::json nav_json(const tools::NavErrorStats& s) {
  return {{"samples", s.samples},
          {"attitude_samples", s.attitude_samples},
          {"position_rms_m", s.pos_rms_m},
          {"velocity_rms_mps", s.vel_rms_mps},
          {"tilt_rms_deg", s.tilt_rms_deg},
          {"heading_rms_deg", s.heading_rms_deg},
          {"heading_final_deg", s.heading_final_deg}};
}

void write_traces(const std::string& path, const tools::DiagnosisRun& r) {
  tools::TextOutput out(path);  // docs/faults.md: complete or not there
  std::ostream& f = out.os();
  const auto& cands = tools::diagnosis_candidates();
  f << "t_s,pr_rms_m,prr_rms_mps,pos_rms_m,vel_rms_mps,heading_err_deg";
  for (int c : r.active) {
    const std::string n = tools::candidate_name(cands[static_cast<std::size_t>(c)]);
    f << "," << n << "," << n << "_sigma";
  }
  f << "\n";
  char buf[64];
  for (std::size_t k = 0; k < r.t_s.size(); ++k) {
    std::snprintf(buf, sizeof buf, "%.3f", r.t_s[k]);
    f << buf << "," << r.pr_rms_m[k] << "," << r.prr_rms_mps[k] << "," << r.pos_rms_m[k] << "," << r.vel_rms_mps[k]
      << ",";
    if (std::isfinite(r.heading_err_deg[k])) f << r.heading_err_deg[k];
    for (std::size_t a = 0; a < r.active.size(); ++a) f << "," << r.est_trace[k][a] << "," << r.sigma_trace[k][a];
    f << "\n";
  }
  out.commit();
}


nlohmann::json segment_json(const sim::Segment& s) {
  const char* dir = s.direction == sim::TurnDirection::kLeft ? "left" : "right";
  nlohmann::json j{{"type", sim::to_string(s.type)}};
  switch (s.type) {
    case sim::SegmentType::kStraight: j["duration_s"] = s.duration_s; break;
    case sim::SegmentType::kTurn:
      j["direction"] = dir;
      j["bank_deg"] = s.bank_deg;
      j["heading_change_deg"] = s.heading_change_deg;
      j["roll_time_s"] = s.roll_time_s;
      break;
    case sim::SegmentType::kSpeedChange:
      j["duration_s"] = s.duration_s;
      j["delta_speed_mps"] = s.delta_speed_mps;
      break;
    case sim::SegmentType::kClimb:
      j["duration_s"] = s.duration_s;
      j["flight_path_deg"] = s.flight_path_deg;
      j["transition_s"] = s.transition_s;
      break;
    case sim::SegmentType::kRoll:
      j["duration_s"] = s.duration_s;
      j["direction"] = dir;
      j["bank_deg"] = s.bank_deg;
      j["roll_time_s"] = s.roll_time_s;
      break;
    case sim::SegmentType::kCrab:
      j["duration_s"] = s.duration_s;
      j["direction"] = dir;
      j["crab_deg"] = s.crab_deg;
      j["transition_s"] = s.transition_s;
      break;
  }
  return j;
}

/// A confounded finding's `separation` (docs/diagnosis-separation.md); k: the finding's index.
nlohmann::json separation_json(const tools::Separation& s, const std::vector<tools::SeparationTrial>& trials,
                               std::size_t k) {
  const auto num_or_null = [](bool ok, double v) { return ok && std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json segs = nlohmann::json::array();
  for (const sim::Segment& g : s.segments) segs.push_back(segment_json(g));
  nlohmann::json tried = nlohmann::json::array();
  for (const tools::SeparationTrial& t : trials)
    tried.push_back({{"label", t.label},
                     {"added_s", t.added_s},
                     {"predicted_correlation", num_or_null(t.evaluated && k < t.correlation.size(),
                                                           k < t.correlation.size() ? t.correlation[k] : NAN)},
                     {"error", t.error}});
  return {{"members", s.members},
          {"max_correlation", s.max_correlation},
          {"flown_correlation", s.flown_correlation},
          {"predicted", s.predicted},
          {"note", s.note},
          {"label", s.label},
          {"segments", s.segments_toml},
          {"segment_list", segs},
          {"added_s", s.added_s},
          {"scenario_toml", s.scenario_toml.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.scenario_toml)},
          {"predicted_correlation", num_or_null(s.predicted, s.predicted_correlation)},
          {"member_correlation", s.member_correlation},
          {"member_sigma", s.member_sigma},
          {"separates", s.separates},
          {"tried", tried}};
}

/// The report's interval cell: [lo, hi] (method), not bounded / not calibrated when so.
std::string interval_cell(const tools::ReportedInterval& iv) {
  char b[160];
  std::snprintf(b, sizeof b, "[%.4g, %.4g] (%s%s%s)", iv.lo, iv.hi, iv.is_profile() ? "profile" : "filter",
                iv.bounded ? "" : ", not bounded", iv.model_agrees ? "" : ", NOT CALIBRATED");
  return b;
}

/// The JSON interval_95 object (docs/diagnosis-intervals.md).
nlohmann::json interval_json(const tools::ReportedInterval& iv) {
  return {{"lo", iv.lo},
          {"hi", iv.hi},
          {"method", iv.method},
          {"estimate", iv.estimate},
          {"bounded", iv.bounded},
          {"runs", iv.runs},
          {"deviance_at_filter_estimate", iv.deviance_at_filter},
          {"model_agrees", iv.model_agrees}};
}

/// A profile interval whose filter estimate it disagrees with (tools::ProfileInterval::model_agrees).
void print_disagreement(double deviance) {
  std::printf("  NOT CALIBRATED: the filter's estimate lies at deviance %.1f of the profile likelihood (> %.2f, p < 0.001):\n"
              "  the filter and the profile disagree, so the model does not describe this component's effect on these\n"
              "  data (an unmodelled effect or a wrong noise model); the interval assumes it does "
              "(docs/diagnosis-intervals.md)\n",
              deviance, tools::kModelAgreementDeviance);
}

/// A separable finding's headline on the terminal: the profile's maximum when the interval is a
/// profile (the filter's own figure beside it, labelled), else the filter's estimate.
void print_finding_headline(const tools::Finding& f) {
  const std::string name = std::string(fsw::effect_info(f.effect).name) + (f.component.empty() ? "" : "." + f.component);
  if (f.estimate_method == "profile_maximum")
    std::printf("finding: %s = %.4g %s (profile-likelihood maximum), 95%% interval [%.4g, %.4g] %s%s; the filter's own "
                "estimate %.4g +- %.3g %s (z^2 %.1f, p %.2g)\n",
                name.c_str(), f.estimate, f.unit.c_str(), f.interval.lo, f.interval.hi, f.unit.c_str(),
                f.interval.bounded ? "" : " (not bounded within the range searched)", f.filter_estimate, f.filter_sigma,
                f.unit.c_str(), f.z2, f.p_value);
  else
    std::printf("finding: %s = %.4g +- %.3g %s (filter), 95%% interval [%.4g, %.4g] %s (%s) (z^2 %.1f, p %.2g)\n",
                name.c_str(), f.estimate, f.sigma, f.unit.c_str(), f.interval.lo, f.interval.hi, f.unit.c_str(),
                f.interval.method.c_str(), f.z2, f.p_value);
}

/// A group member's "alone" value as shown: the profile's maximum with the filter's figure beside
/// it when the member's interval is a profile, else the filter's estimate +- sigma.
std::string member_headline(const tools::GroupMember& m) {
  char b[160];
  if (m.alone_interval.is_profile())
    std::snprintf(b, sizeof b, "%.4g (profile maximum; filter %.4g +- %.3g)", m.alone_interval.estimate, m.alone_estimate,
                  m.alone_sigma);
  else
    std::snprintf(b, sizeof b, "%.4g +- %.3g (filter)", m.alone_estimate, m.alone_sigma);
  return b;
}

std::string finding_label(const tools::Finding& f) {
  return std::string(fsw::effect_info(f.effect).name) + (f.component.empty() ? "" : "." + f.component) +
         (f.separable() ? "" : " (group of " + std::to_string(f.group.size()) + ")");
}

std::string applied_text(const std::vector<tools::AppliedCorrection>& applied) {
  if (applied.empty()) return "nothing (the recording as given)";
  std::string t;
  for (const tools::AppliedCorrection& a : applied) t += (t.empty() ? "" : ", ") + a.name + " " + fmt("%+.5g", a.value) + " " + a.unit;
  return t;
}

/// The chain in the JSON (docs/diagnosis.md, "The chain").
nlohmann::json chain_json(const tools::DiagnosisChain& ch) {
  const auto corr = [](const tools::AppliedCorrection& a) {
    return nlohmann::json{{"candidate", a.name}, {"value", a.value}, {"total", a.total}, {"unit", a.unit},
                          {"source", a.source}, {"stage", a.stage},
                          {"from_group", a.from_group}};
  };
  nlohmann::json stages = nlohmann::json::array();
  for (const tools::ChainStage& st : ch.stages) {
    nlohmann::json before = nlohmann::json::array(), found = nlohmann::json::array();
    for (const tools::AppliedCorrection& a : st.applied_before) before.push_back(corr(a));
    for (const tools::Finding& f : st.findings)
      found.push_back({{"candidate", std::string(fsw::effect_info(f.effect).name) + (f.component.empty() ? "" : "." + f.component)},
                       {"separable", f.separable()},
                       {"estimate", f.estimate},
                       {"estimate_method", f.estimate_method},
                       {"filter_estimate", f.filter_estimate},
                       {"filter_sigma", f.filter_sigma},
                       {"interval_95", interval_json(f.interval)},
                       {"statistic", f.z2},
                       {"unit", f.unit}});
    stages.push_back({{"stage", st.stage},
                      {"applied_before", before},
                      {"findings", found},
                      {"baseline_log_likelihood", st.base_log_likelihood},
                      {"common_measurements", st.common_measurements},
                      {"baseline_nis_mean", st.base_nis},
                      {"extended_nis_mean", st.extended_nis},
                      {"extended_log_likelihood_gain", st.extended_gain},
                      {"applied_after", st.applied_after.empty() ? nlohmann::json(nullptr) : nlohmann::json(st.applied_after)}});
  }
  nlohmann::json applied = nlohmann::json::array();
  for (const tools::AppliedCorrection& a : ch.applied) applied.push_back(corr(a));
  const tools::MountingEstimate& m = ch.mounting;
  nlohmann::json mounting = nullptr;
  if (m.searched)
    mounting = {{"quantity", "mounting yaw: added to init.heading_offset_deg (track initialisation)"},
                {"found", m.found},
                {"yaw_deg", m.yaw_deg},
                {"interval_95_deg", {m.lo_deg, m.hi_deg}},
                {"method", "profile_likelihood over the initial heading offset (ungated baseline runs)"},
                {"deviance_at_configured", m.deviance_at_configured},
                {"runs", m.runs},
                {"curve", {{"value_deg", m.theta_deg}, {"deviance", m.deviance}}}};
  return {{"mounting", mounting},
          {"mounting_from_travel", tools::mounting_json(ch.travel)},
          {"stages", stages},
          {"applied", applied},
          {"not_found_after_corrections", ch.vanished}};
}

void print_chain(const tools::DiagnosisChain& ch) {
  const tools::MountingEstimate& m = ch.mounting;
  if (m.searched)
    std::printf("mounting yaw (track initialisation): %s (%d runs; deviance at the configured heading offset %.1f)\n",
                m.found ? ("found " + fmt("%.2f", m.yaw_deg) + " deg, 95% [" + fmt("%.2f", m.lo_deg) + ", " + fmt("%.2f", m.hi_deg) +
                           "] deg, applied to init.heading_offset_deg before every search")
                              .c_str()
                        : "none (no rotated start fits better than the configured one)",
                m.runs, m.deviance_at_configured);
  for (const std::string& line : tools::mounting_terminal_lines(ch.travel)) std::printf("%s\n", line.c_str());
  for (const tools::ChainStage& st : ch.stages) {
    std::string found;
    for (const tools::Finding& f : st.findings)
      found += (found.empty() ? "" : ", ") + finding_label(f) + (f.separable() ? " " + fmt("%.4g", f.estimate) + " " + f.unit : "");
    std::printf("chain stage %d, after %s: %s; baseline log-likelihood %.1f over %d measurements common to every stage "
                "(extended %+.1f)%s\n",
                st.stage, applied_text(st.applied_before).c_str(), found.empty() ? "no finding" : found.c_str(),
                st.base_log_likelihood, st.common_measurements, st.extended_gain,
                st.applied_after.empty() ? "" : ("; applies " + st.applied_after).c_str());
  }
  if (!ch.vanished.empty()) {
    std::string v;
    for (const std::string& n : ch.vanished) v += (v.empty() ? "" : ", ") + n;
    std::printf("chain: not found once the corrections before them are applied (not reported): %s\n", v.c_str());
  }
}

void chain_md(std::ostream& md, const tools::DiagnosisChain& ch) {
  md << tools::mounting_report_md(ch.travel);
  md << "## The chain: findings that survive their predecessors\n\n";
  if (ch.mounting.searched)
    md << "Mounting yaw (the track initialisation's heading offset, profile likelihood of the ungated baseline over "
       << ch.mounting.runs << " runs): "
       << (ch.mounting.found ? "**" + fmt("%.2f", ch.mounting.yaw_deg) + " deg**, 95% [" + fmt("%.2f", ch.mounting.lo_deg) +
                                   ", " + fmt("%.2f", ch.mounting.hi_deg) + "] deg, applied to `init.heading_offset_deg` before every search"
                             : std::string("none (no rotated start fits better than the configured one)"))
       << ".\n\n";
  md << ""
        "After each timing or geometry finding the recording (or the antenna in the model) is corrected by it, at "
        "the profile likelihood's maximum, and searched again; a finding is reported only if the search after every "
        "correction before it still finds it (docs/diagnosis.md). The baseline log-likelihood is over the measurements "
        "common to every stage.\n\n"
        "| stage | applied before | found | baseline log-likelihood | extended model gain | applied after |\n"
        "|---|---|---|---|---|---|\n";
  for (const tools::ChainStage& st : ch.stages) {
    std::string found;
    for (const tools::Finding& f : st.findings)
      found += (found.empty() ? "" : "; ") + finding_label(f) +
               (f.separable() ? " " + fmt("%.4g", f.estimate) + " " + f.unit + " " + interval_cell(f.interval) : "");
    md << "| " << st.stage << " | " << applied_text(st.applied_before) << " | " << (found.empty() ? "nothing" : found)
       << " | " << fmt("%.1f", st.base_log_likelihood) << " (" << st.common_measurements << ") | "
       << fmt("%+.1f", st.extended_gain) << " | " << (st.applied_after.empty() ? "(end)" : st.applied_after) << " |\n";
  }
  md << "\n";
  if (!ch.vanished.empty()) {
    md << "Found at an earlier stage and not once the corrections before them were applied (side effects, not "
          "reported): ";
    for (std::size_t i = 0; i < ch.vanished.size(); ++i) md << (i ? ", " : "") << "`" << ch.vanished[i] << "`";
    md << ".\n\n";
  }
}

nlohmann::json evidence_json(const tools::RecordingEvidence& ev) {
  nlohmann::json checks = nlohmann::json::array();
  for (const tools::EvidenceCheck& c : ev.checks)
    checks.push_back({{"finding", c.finding},
                      {"source", c.source},
                      {"evidence", c.evidence},
                      {"tolerance", c.tolerance},
                      {"unit", c.unit},
                      {"finding_estimate", c.finding_estimate},
                      {"finding_interval_95", {c.finding_lo, c.finding_hi}},
                      {"contradicts", c.contradicts},
                      {"note", c.note}});
  nlohmann::json j;
  j["imu_counter"] = ev.counter_samples > 0 ? nlohmann::json{{"samples", ev.counter_samples},
                                                             {"nominal_rate_hz", ev.counter_rate_hz},
                                                             {"tag_stretch_ppm", ev.counter_stretch_ppm},
                                                             {"residual_rms_s", ev.counter_residual_rms_s}}
                                            : nlohmann::json(nullptr);
  j["clock_fit"] = ev.has_clock_fit ? nlohmann::json{{"summary", ev.summary_path},
                                                     {"drift_ppm", ev.clock_fit_drift_ppm},
                                                     {"residual_rms_s", ev.clock_fit_residual_rms_s}}
                                    : nlohmann::json(nullptr);
  j["tick_mapping"] = ev.has_tick_ratio ? nlohmann::json{{"tag_stretch_ppm", ev.tick_stretch_ppm}} : nlohmann::json(nullptr);
  j["summary_note"] = ev.summary_note;
  j["imu_counter_note"] = ev.counter_note;
  j["reference_lag"] = ev.has_reference_lag ? nlohmann::json{{"reference", ev.reference_kind},
                                                             {"imu_lag_s", ev.reference_lag_s},
                                                             {"correlation", ev.reference_correlation},
                                                             {"note", ev.reference_note},
                                                             {"intervals", ev.reference_samples}}
                                            : nlohmann::json(nullptr);
  j["checks"] = checks;
  return j;
}

void print_evidence(const tools::RecordingEvidence& ev) {
  if (ev.counter_samples > 0)
    std::printf("evidence: the IMU's sample counter against its tags: stretch %+.1f ppm at a nominal %.0f Hz (%d samples, "
                "residual %.2g s RMS)\n",
                ev.counter_stretch_ppm, ev.counter_rate_hz, ev.counter_samples, ev.counter_residual_rms_s);
  if (!ev.counter_note.empty()) std::printf("evidence: %s\n", ev.counter_note.c_str());
  if (ev.has_tick_ratio)
    std::printf("evidence: the import mapped the IMU's own tick onto GPS time stretched by %+.1f ppm (%s)\n",
                ev.tick_stretch_ppm, ev.summary_path.c_str());
  if (ev.has_clock_fit)
    std::printf("evidence: the import's clock pair (%s): local clock drift %+.2f ppm against GPS\n", ev.summary_path.c_str(),
                ev.clock_fit_drift_ppm);
  if (ev.has_reference_lag)
    std::printf("evidence: the IMU's rate against the reference's %s rate: IMU tags lag %+.4f s (correlation %.3f)%s%s\n",
                ev.reference_kind.c_str(), ev.reference_lag_s, ev.reference_correlation,
                ev.reference_note.empty() ? "" : "; ", ev.reference_note.c_str());
  for (const tools::EvidenceCheck& c : ev.checks)
    std::printf("evidence on %s = %.4g %s [%.4g, %.4g]: %s says %+.4g %s (tolerance %.3g)%s\n", c.finding.c_str(),
                c.finding_estimate, c.unit.c_str(), c.finding_lo, c.finding_hi, c.source.c_str(), c.evidence,
                c.unit.c_str(), c.tolerance, c.contradicts ? ": CONTRADICTED by the recording's own evidence" : ": consistent");
}

void evidence_md(std::ostream& md, const tools::RecordingEvidence& ev) {
  md << "## Evidence the recording carries\n\n";
  if (ev.counter_samples == 0 && !ev.has_clock_fit && !ev.has_reference_lag && ev.counter_note.empty() && !ev.has_tick_ratio) {
    md << "None: no IMU sample counter, no import clock pair" << (ev.summary_note.empty() ? "" : " (" + ev.summary_note + ")")
       << ", no reference with a usable rate.\n\n";
    return;
  }
  if (ev.counter_samples > 0)
    md << "- The IMU's own sample counter against its time tags: the tags are stretched by "
       << fmt("%+.1f", ev.counter_stretch_ppm) << " ppm against a nominal " << fmt("%.0f", ev.counter_rate_hz) << " Hz ("
       << ev.counter_samples << " samples).\n";
  if (!ev.counter_note.empty()) md << "- " << ev.counter_note << ".\n";
  if (ev.has_tick_ratio)
    md << "- The import mapped the IMU's own tick onto GPS time stretched by " << fmt("%+.1f", ev.tick_stretch_ppm)
       << " ppm (`imu.seconds_per_imu_second` of `" << ev.summary_path << "`).\n";
  if (ev.has_clock_fit)
    md << "- The import's clock pair (`" << ev.summary_path << "`): the local clock drifts "
       << fmt("%+.2f", ev.clock_fit_drift_ppm) << " ppm against GPS time.\n";
  else if (!ev.summary_path.empty())
    md << "- `" << ev.summary_path << "`: " << ev.summary_note << ".\n";
  if (ev.has_reference_lag)
    md << "- The reference's " << ev.reference_kind << " rate against the IMU's gyro rate: the IMU tags lag "
       << fmt("%+.4f", ev.reference_lag_s) << " s (correlation " << fmt("%.3f", ev.reference_correlation) << ")"
       << (ev.reference_note.empty() ? "" : "; " + ev.reference_note) << ".\n";
  md << "\n";
  if (ev.checks.empty()) {
    md << "No timing finding to check against it.\n\n";
    return;
  }
  md << "| finding | estimate | 95% interval | evidence | what it says | tolerance | verdict |\n|---|---|---|---|---|---|---|\n";
  for (const tools::EvidenceCheck& c : ev.checks)
    md << "| " << c.finding << " | " << fmt("%.4g", c.finding_estimate) << " " << c.unit << " | [" << fmt("%.4g", c.finding_lo) << ", "
       << fmt("%.4g", c.finding_hi) << "] | " << c.source << " | " << fmt("%+.4g", c.evidence) << " " << c.unit << " | "
       << fmt("%.3g", c.tolerance) << " | " << (c.contradicts ? "**contradicted**" : "consistent") << " |\n";
  md << "\nNothing is overridden: the finding stays as the likelihood gives it; a contradicted one says that the data "
        "and the recording's own clocks or reference disagree, and one of them (or the model) is wrong.\n\n";
}

}  // namespace

void register_diagnose(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "diagnose",
      "Find what the navigation model misses in a recording (LCM log: IMU, GNSS_RAW, GPS_ALMANAC; TRUTH only to "
      "score): tests every component of the effect catalogue as an extension of the baseline model with a "
      "chi-square test at a stated family-wise false-alarm rate, names the significant ones (and those the data "
      "cannot tell apart), re-runs with the extended model and measures the gain.");
  sub->add_option("--log", diagnose_opt.log, "LCM log to diagnose")->required()->check(CLI::ExistingFile);
  sub->add_option("--json", diagnose_opt.json, "write the result as JSON (docs/diagnosis.md)")->required();
  sub->add_option("--report", diagnose_opt.report, "write a markdown report with plots and CSV traces into this directory");
  // Not model_help(): in the diagnosis the 15-state baseline has no consider states; what it leaves
  // out (the misalignments among them) is what the catalogue tests.
  sub->add_option("--baseline", diagnose_opt.baseline,
                  "baseline model the effect catalogue extends (with the receiver clock and Gauss-Markov GPS "
                  "errors in both): 15 (position, velocity, attitude, gyro and accelerometer biases; the "
                  "misalignments are not modelled, they are among the components tested), 24 (the 15 plus 3 "
                  "accelerometer and 6 gyro misalignments, estimated)")
      ->check(CLI::IsMember(model_names(kFlightModels)))
      ->capture_default_str();
  sub->add_option("--alpha", diagnose_opt.alpha, "family-wise false-alarm rate of the diagnosis")
      ->check(CLI::Range(1e-9, 0.5))
      ->capture_default_str();
  sub->add_option("--intervals", diagnose_opt.intervals,
                  "95% interval of each finding and group member alone: profile (the profile likelihood over the whole recording, "
                  "docs/diagnosis-intervals.md) or filter (the filter's estimate +- 1.96 sigma, faster)")
      ->check(CLI::IsMember({"profile", "filter"}))
      ->capture_default_str();
  sub->add_option("--profile", diagnose_opt.profile,
                  "also the profile-likelihood 95% interval of this component (effect.component, catalogue name) on "
                  "top of the extended model, finding or not (repeatable; JSON `profiles`): an independent check of "
                  "a value known from elsewhere");
  sub->add_flag("--profile-only", diagnose_opt.profile_only,
               "no search: only the baseline run and the --profile components on top of it, each with the filter's "
               "and the profile-likelihood interval (the coverage study, docs/diagnosis-intervals.md)");
  sub->add_flag("--no-chain", diagnose_opt.no_chain,
               "search once: do not apply a timing or geometry finding (time offset, clock drift, lever arm) to the "
               "recording and search again from the corrected data (docs/diagnosis.md, the chain)");
  sub->add_option("--flight-config,--filter-config", diagnose_opt.flight_config,
                  "flight configuration TOML for the data set (config/README.md): sensor noise, rates, GNSS input "
                  "(raw or solutions), initialisation, priors and outage pattern of the diagnosis, applied on top of the "
                  "shipped flight configuration <data dir>/config/default.toml (default: none, the shipped file alone)");
}

namespace {

/// One diagnose invocation's state, handed from step to step of run_diagnose.
struct Diagnosis {
  tools::DiagnosisConfig cfg;
  tools::RecordedData data;  ///< as loaded; after a chained search the chain's corrected recording
  std::string load_report;
  tools::RecordingEvidence evidence;  ///< what the recording as given says of itself
  tools::DiagnosisResult r;
  tools::DiagnosisChain chain;
  bool chained = false;
  nlohmann::json profiles;
  std::vector<tools::Separation> seps;
  std::vector<tools::SeparationTrial> trials;
  std::vector<std::string> applied_names;  ///< the corrections the chain applied, each once
  std::string ext_name;                    ///< the extended model's name
};

double rms(const tools::InnovationStats& i, bool pvt) { return pvt ? i.pos_rms_m : i.pr_rms_m; }
double rms_rate(const tools::InnovationStats& i, bool pvt) { return pvt ? i.vel_rms_mps : i.prr_rms_mps; }
std::string heading_text(const tools::NavErrorStats& n) {
  char b[64] = "";
  if (n.attitude_samples > 0) std::snprintf(b, sizeof b, ", heading %.4f deg", n.heading_rms_deg);
  return std::string(b);
}

/// The configuration (the shipped config/default.toml with --flight-config on top, validated before
/// the log is read: filter, GNSS input, priors, outages), the recording and its own evidence.
void load(Diagnosis& d) {
  tools::DiagnosisConfig& cfg = d.cfg;
  tools::RecordedData& data = d.data;
  std::string& load_report = d.load_report;
  tools::apply_flight_config(cfg, cfg::flight_config(diagnose_opt.flight_config));
  std::string err;
  if (!tools::load_recorded_data(diagnose_opt.log, data, err, load_report)) throw std::runtime_error(err);
  std::printf("diagnose: %s: %s\n", diagnose_opt.log.c_str(), load_report.c_str());
  // What the recording as given says of itself (before any correction of the chain).
  d.evidence = tools::recording_evidence(data, diagnose_opt.log);
  cfg.alpha = diagnose_opt.alpha;
  cfg.profile_intervals = diagnose_opt.intervals == "profile";
  if (!tools::set_diagnosis_baseline(cfg, parse_model(diagnose_opt.baseline, "--baseline", kFlightModels)))
    throw std::runtime_error("--baseline: " + diagnose_opt.baseline + " is not a diagnosis baseline");
}

/// The search: the baseline alone (--profile-only), one search (--no-chain) or the chain.
void search(Diagnosis& d) {
  tools::DiagnosisConfig& cfg = d.cfg;
  tools::RecordedData& data = d.data;
  tools::DiagnosisResult& r = d.r;
  tools::DiagnosisChain& chain = d.chain;
  const auto progress = [](const std::string& m) {
    std::printf("  %s\n", m.c_str());
    tools::throw_if_interrupted("diagnose stopped (" + m + "); no output written");
  };
  if (diagnose_opt.profile_only && diagnose_opt.profile.empty()) throw std::runtime_error("--profile-only needs at least one --profile");
  d.chained = !diagnose_opt.profile_only && !diagnose_opt.no_chain;
  if (diagnose_opt.profile_only) {
    r.baseline = fsw::to_string(cfg.baseline);
    r.base = tools::run_diagnosis_model(data, cfg, cfg.baseline_states);
    r.extended = r.base;
  } else if (diagnose_opt.no_chain) {
    r = tools::diagnose(data, cfg, progress);
  } else {
    // The chain (docs/diagnosis.md): the last search on the corrected recording, its findings those
    // that survived every correction before them, scored against the recording as given.
    chain = tools::diagnose_chain(data, cfg, progress);
    r = chain.last;
    r.findings = chain.findings;
    r.base = chain.first.base;
    tools::compare_likelihood(r.base, r.extended);
    if (chain.recording_corrected) data = std::move(chain.corrected);
    cfg = chain.corrected_cfg;
  }
  tools::throw_if_interrupted("diagnose stopped; no output written");
  if (!r.base.initialised) throw std::runtime_error("the flight software never initialised on this log");
}

/// The --profile components: each one's profile-likelihood interval on top of the extended model.
nlohmann::json profile_components(const Diagnosis& d) {
  const tools::DiagnosisConfig& cfg = d.cfg;
  const tools::RecordedData& data = d.data;
  const tools::DiagnosisResult& r = d.r;
  nlohmann::json profiles = nlohmann::json::array();
  for (const std::string& name : diagnose_opt.profile) {
    const int c = tools::candidate_index(name);
    if (c < 0) throw std::runtime_error("--profile: unknown component '" + name + "' (catalogue names, docs/diagnosis.md)");
    const fsw::Effect e = tools::diagnosis_candidates()[static_cast<std::size_t>(c)].effect;
    if (!tools::profile_supported(e)) throw std::runtime_error("--profile: " + name + " cannot be held fixed (delay scales)");
    double x = 0.0, s = 0.0;
    const tools::ProfileInterval pi = tools::profile_component(data, cfg, r.extended.active, c, x, s);
    if (pi.runs == 0) throw std::runtime_error("--profile " + name + ": the model did not initialise");
    if (!pi.available)
      throw std::runtime_error("--profile " + name + ": the runs at different values share only " +
                               std::to_string(pi.measurements) +
                               " measurements (an EKF schedule that moves with the value): no profile likelihood");
    std::printf("profile: %s = %.4g +- %.3g %s (filter); 95%% interval [%.4g, %.4g], maximum %.4g (profile likelihood, %d runs, "
                "%d common measurements%s)\n",
                name.c_str(), x, s, fsw::effect_info(e).unit, pi.lo, pi.hi, pi.estimate, pi.runs, pi.measurements,
                pi.lo_bounded && pi.hi_bounded ? "" : ", not bounded within the range searched");
    if (!pi.model_agrees()) print_disagreement(pi.deviance_at_filter);
    profiles.push_back({{"candidate", name},
                        {"unit", fsw::effect_info(e).unit},
                        {"filter_estimate", x},
                        {"filter_sigma", s},
                        {"interval_95", interval_json(tools::reported_interval(pi))},
                        {"curve", {{"value", pi.theta}, {"deviance", pi.deviance}}}});
    profiles.back()["interval_95"]["measurements"] = pi.measurements;
  }
  return profiles;
}

/// The manoeuvre that separates each confounded group (docs/diagnosis-separation.md).
void separate_groups(Diagnosis& d) {
  const tools::DiagnosisResult& r = d.r;
  const tools::FlownScenario flown = tools::scenario_from_sidecar(diagnose_opt.log);
  const auto t_sep = std::chrono::steady_clock::now();
  d.seps = tools::suggest_separations(r, d.cfg, flown, [](const std::string& m) {
        std::printf("  %s\n", m.c_str());
        tools::throw_if_interrupted("diagnose stopped (" + m + "); no output written");
      }, &d.trials);
  tools::throw_if_interrupted("diagnose stopped; no output written");
  const double sep_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_sep).count();
  bool any_group = false;
  for (const tools::Finding& f : r.findings) any_group = any_group || !f.separable();
  if (any_group) std::printf("  separation suggestions: %.1f s\n", sep_s);
}

/// The evidence checked against the findings; after the chain, the reference lag on the corrected
/// recording. Then the extended model's name: the corrections the chain applied to the data or the
/// antenna, then the states added in its last search.
void check_evidence_and_name_model(Diagnosis& d) {
  tools::RecordingEvidence& evidence = d.evidence;
  const tools::DiagnosisChain& chain = d.chain;
  const tools::RecordedData& data = d.data;
  if (d.chained && evidence.has_reference_lag) {
    // The lag on the corrected recording (the drift's re-timing included) plus the offset applied:
    // the frame in which the chain states its offset.
    double offset_applied_s = 0.0;
    for (const tools::AppliedCorrection& a : chain.applied)
      if (a.name == "imu_gnss_time_offset") offset_applied_s += a.value;
    const double as_given_s = evidence.reference_lag_s;
    tools::reference_lag(evidence, data);  // data: the chain's corrected recording here
    evidence.reference_lag_s += offset_applied_s;
    char b[200];
    std::snprintf(b, sizeof b,
                  "measured on the recording with the chain's corrections applied, plus the %+.4f s offset applied "
                  "(on the recording as given: %+.4f s)",
                  offset_applied_s, as_given_s);
    evidence.reference_note = b;
  }
  tools::check_findings(evidence, d.r.findings);
  std::vector<std::string>& applied_names = d.applied_names;
  for (const tools::AppliedCorrection& a : chain.applied)
    if (std::find(applied_names.begin(), applied_names.end(), a.name) == applied_names.end()) applied_names.push_back(a.name);
  std::string& ext_name = d.ext_name;
  ext_name = diagnose_opt.baseline;
  for (const std::string& s : applied_names) ext_name += "+" + s + "(applied)";
  for (const std::string& s : d.r.extended_model) ext_name += "+" + s;
}

nlohmann::json findings_json(const Diagnosis& d) {
  const tools::DiagnosisResult& r = d.r;
  const std::vector<tools::Separation>& seps = d.seps;
  const std::vector<tools::SeparationTrial>& trials = d.trials;
  nlohmann::json findings = nlohmann::json::array();
  for (std::size_t fi = 0; fi < r.findings.size(); ++fi) {
    const tools::Finding& f = r.findings[fi];
    const tools::ReportedInterval filter_iv = tools::filter_interval(f.filter_estimate, f.filter_sigma);
    nlohmann::json cw = nlohmann::json::array();
    for (const auto& c : f.confounded_with) cw.push_back({{"candidate", c.first}, {"correlation", c.second}});
    nlohmann::json group = nlohmann::json::array();
    for (const tools::GroupMember& m : f.group)
      group.push_back({{"candidate", m.name},
                       {"correlation", m.correlation},
                       {"multiple_correlation", m.multiple_correlation},
                       {"alone_estimate", m.alone_estimate},
                       {"alone_headline_estimate", m.alone_interval.is_profile() ? m.alone_interval.estimate : m.alone_estimate},
                       {"alone_sigma", m.alone_sigma},
                       {"alone_statistic", m.alone_z2},
                       {"alone_interval_95", interval_json(m.alone_interval)},
                       {"unit", m.unit},
                       {"prior_sigma", m.prior_sigma},
                       {"prior_z", m.prior_z},
                       {"plausibility", m.plausibility}});
    findings.push_back({{"effect", fsw::effect_info(f.effect).name},
                        {"component", f.component},
                        {"estimate", f.estimate},
                        {"sigma", f.sigma},
                        {"estimate_method", f.estimate_method},
                        {"filter_estimate", f.filter_estimate},
                        {"filter_sigma", f.filter_sigma},
                        {"unit", f.unit},
                        {"statistic", f.z2},
                        {"dof", f.dof},
                        {"p_value", f.p_value},
                        {"threshold", f.threshold_z2},
                        {"separable", f.separable()},
                        {"interval_95", interval_json(f.interval)},
                        {"filter_interval_95", {filter_iv.lo, filter_iv.hi}},
                        {"confounded_with", cw},
                        {"group", group}});
    if (!f.separable()) findings.back()["separation"] = separation_json(seps[fi], trials, fi);
  }
  return findings;
}

nlohmann::json gain_json(const Diagnosis& d) {
  const tools::DiagnosisConfig& cfg = d.cfg;
  const tools::DiagnosisResult& r = d.r;
  nlohmann::json gain;
  gain["innovations"] = {{"before", innovations_json(r.base.innovations)},
                         {"after", innovations_json(r.extended.innovations)},
                         {"log_likelihood_gain", r.extended.innovations.log_likelihood - r.base.innovations.log_likelihood}};
  if (r.base.nav.available && r.extended.nav.available)
    gain["navigation"] = {{"reference", "TRUTH channel"},
                          {"scored_from_s_after_init", cfg.gain_skip_s},
                          {"before", nav_json(r.base.nav)},
                          {"after", nav_json(r.extended.nav)}};
  else
    gain["navigation"] = nullptr;
  if (r.base.outages.windows > 0 || r.base.outages.reacquisitions > 0) {
    auto oj = [](const tools::OutageStats& o) {
      nlohmann::json oj_{{"windows", o.windows},
                       {"epochs_withheld", o.epochs_withheld},
                       {"reacquisitions", o.reacquisitions},
                       {"reacquisition_nis_mean", o.reacquisitions > 0 ? nlohmann::json(o.reacquisition_nis_mean) : nullptr}};
      const bool ref = o.windows > 0;  // the reference-based scores
      oj_["horizontal_rms_m"] = ref ? nlohmann::json(o.horizontal_rms_m) : nullptr;
      oj_["horizontal_max_m"] = ref ? nlohmann::json(o.horizontal_max_m) : nullptr;
      oj_["velocity_rms_mps"] = ref ? nlohmann::json(o.velocity_rms_mps) : nullptr;
      oj_["predicted_horizontal_rms_m"] = ref ? nlohmann::json(o.predicted_horizontal_rms_m) : nullptr;
      oj_["horizontal_nees_mean"] = ref ? nlohmann::json(o.horizontal_nees_mean) : nullptr;
      return oj_;
    };
    gain["outages"] = {{"length_s", cfg.outage_length_s},
                       {"period_s", cfg.outage_period_s},
                       {"first_s_after_init", cfg.outage_first_s},
                       {"before", oj(r.base.outages)},
                       {"after", oj(r.extended.outages)}};
  } else {
    gain["outages"] = nullptr;
  }
  return gain;
}

/// The JSON of --json (docs/diagnosis.md).
nlohmann::json diagnosis_json(const Diagnosis& d) {
  const tools::DiagnosisConfig& cfg = d.cfg;
  const tools::RecordedData& data = d.data;
  const tools::DiagnosisResult& r = d.r;
  const std::string& load_report = d.load_report;
  const auto& cands = tools::diagnosis_candidates();
  nlohmann::json j;
  j["baseline"] = diagnose_opt.baseline;
  j["log"] = diagnose_opt.log;
  j["filter_config"] = diagnose_opt.flight_config;
  j["gnss_source"] = cfg::to_string(cfg.gnss_source);
  j["data"] = {{"imu_samples", data.imu.size()},
               {"gnss_epochs", data.gnss.size()},
               {"gnss_solutions", data.pvt.size()},
               {"truth_samples", data.truth.size()},
               {"damaged_stretches_excluded", data.damaged_stretches},
               {"imu_samples_excluded", data.excluded_imu_samples},
               {"summary", load_report}};
  j["method"] = {{"statistic", "wald_chi2_1"},
                 {"alpha", cfg.alpha},
                 {"tested_components", r.tested},
                 {"threshold", r.threshold_z2},
                 {"max_variance_ratio", cfg.max_variance_ratio},
                 {"max_correlation", cfg.max_correlation},
                 {"intervals", diagnose_opt.intervals}};
  nlohmann::json screening = nlohmann::json::array();
  for (std::size_t c = 0; c < cands.size() && c < r.screening_z2.size(); ++c)
    if (std::find(cfg.baseline_states.begin(), cfg.baseline_states.end(), static_cast<int>(c)) == cfg.baseline_states.end())
      screening.push_back({{"candidate", tools::candidate_name(cands[c])},
                         {"statistic", r.screening_z2[c]},
                         {"variance_ratio", r.screening_ratio[c]}});
  j["screening"] = screening;
  j["unobservable"] = r.unobservable;
  j["confounded_with_baseline"] = r.confounded_with_baseline;
  j["findings"] = findings_json(d);
  j["evidence"] = evidence_json(d.evidence);
  j["chain"] = d.chained ? chain_json(d.chain) : nlohmann::json(nullptr);
  j["profiles"] = d.profiles;
  j["extended_model"] = {{"name", d.ext_name}, {"added_states", r.extended_model}, {"applied_corrections", d.applied_names}};
  j["gain"] = gain_json(d);
  return j;
}


/// What the command prints: the baseline, the chain, the evidence, each finding, the extended model,
/// the coasting through the outages.
void print_summary(const Diagnosis& d) {
  const tools::DiagnosisConfig& cfg = d.cfg;
  const tools::DiagnosisResult& r = d.r;
  const tools::DiagnosisChain& chain = d.chain;
  const bool chained = d.chained;
  const tools::RecordingEvidence& evidence = d.evidence;
  const std::vector<tools::Separation>& seps = d.seps;
  const std::string& ext_name = d.ext_name;
  const bool pvt = cfg.gnss_source == cfg::GnssSource::kPvt;
  std::printf("baseline %s: NIS %.3f, %s innovation RMS %.3f m / %.4f m/s", diagnose_opt.baseline.c_str(),
              r.base.innovations.nis_mean, pvt ? "position/velocity" : "pseudorange/rate", rms(r.base.innovations, pvt),
              rms_rate(r.base.innovations, pvt));
  if (r.base.nav.available)
    std::printf("; position %.2f m, velocity %.3f m/s%s RMS", r.base.nav.pos_rms_m, r.base.nav.vel_rms_mps,
                heading_text(r.base.nav).c_str());
  std::printf("\n");
  tools::print_configuration_warnings(r.base.exec_health);
  if (chained) print_chain(chain);
  print_evidence(evidence);
  if (r.findings.empty()) std::printf("no finding (threshold z^2 %.2f over %d components)\n", r.threshold_z2, r.tested);
  for (std::size_t fi = 0; fi < r.findings.size(); ++fi) {
    const tools::Finding& f = r.findings[fi];
    if (f.separable()) {
      print_finding_headline(f);
      if (!f.interval.model_agrees) print_disagreement(f.interval.deviance_at_filter);
      continue;
    }
    bool applied_member = false;  // the chain applied this group's most plausible member
    for (const tools::AppliedCorrection& a : chain.applied)
      applied_member = applied_member || (a.from_group && a.name == std::string(fsw::effect_info(f.effect).name) +
                                                                         (f.component.empty() ? "" : "." + f.component));
    if (applied_member) {
      print_finding_headline(f);
      std::printf("  applied by the chain as the group's most plausible member (plausibility >= %.2f under the priors; "
                  "the next stage searched the corrected data: the chain above); the data alone do not separate:\n",
                  tools::kChainMemberPlausibility);
    } else {
      std::printf("finding: a group this data cannot separate (z^2 %.1f, %d dof, p %.2g); the cause is one of (or a mix "
                  "of):\n", f.z2, f.dof, f.p_value);
    }
    for (const tools::GroupMember& m : f.group)
      std::printf("  %-26s alone %s %s, 95%% %s = %+.1f prior sigma, plausibility %.2f, rho %+.4f\n",
                  m.name.c_str(), member_headline(m).c_str(), m.unit.c_str(), interval_cell(m.alone_interval).c_str(), m.prior_z,
                  m.plausibility, m.correlation);
    const tools::Separation& sp = seps[fi];
    if (sp.predicted)
      std::printf("  separated by: %s (%.0f s more flight): members' correlation %.4f -> %.3f predicted (%s %.2f)%s\n",
                  sp.label.c_str(), sp.added_s, sp.flown_correlation, sp.predicted_correlation,
                  sp.separates ? "below" : "NOT below", sp.max_correlation,
                  diagnose_opt.report.empty() ? "" : "; scenario file in the report");
    else
      std::printf("  to separate them, fly: %s (%s)\n", sp.label.c_str(), sp.note.c_str());
  }
  if (!r.findings.empty()) {
    std::printf("extended %s: NIS %.3f, innovation RMS %.3f m / %.4f m/s, log-likelihood %+.1f", ext_name.c_str(),
                r.extended.innovations.nis_mean, rms(r.extended.innovations, pvt), rms_rate(r.extended.innovations, pvt),
                r.extended.innovations.log_likelihood - r.base.innovations.log_likelihood);
    if (r.extended.nav.available)
      std::printf("; position %.2f m, velocity %.3f m/s%s RMS", r.extended.nav.pos_rms_m, r.extended.nav.vel_rms_mps,
                  heading_text(r.extended.nav).c_str());
    std::printf("\n");
  }
  if (r.base.outages.windows > 0)
    std::printf("coasting through %d GNSS outages of %.0f s: horizontal error RMS %.2f m (max %.2f) baseline, %.2f m "
                "(max %.2f) extended\n",
                r.base.outages.windows, cfg.outage_length_s, r.base.outages.horizontal_rms_m,
                r.base.outages.horizontal_max_m, r.extended.outages.horizontal_rms_m,
                r.extended.outages.horizontal_max_m);
  if (r.base.outages.windows > 0)
    std::printf("  the filters' own coasting sigma: %.2f m RMS baseline, %.2f m extended; horizontal NEES %.1f and "
                "%.1f (2 if the model explains the coasting error)\n",
                r.base.outages.predicted_horizontal_rms_m, r.extended.outages.predicted_horizontal_rms_m,
                r.base.outages.horizontal_nees_mean, r.extended.outages.horizontal_nees_mean);
  if (r.base.outages.reacquisitions > 0)
    std::printf("re-acquisition after %d GNSS outages of %.0f s (no reference needed): NIS per %s %.1f baseline, %.1f "
                "extended (1 if the model explains its coasting error)\n",
                r.base.outages.reacquisitions, cfg.outage_length_s, pvt ? "position scalar" : "pseudorange",
                r.base.outages.reacquisition_nis_mean, r.extended.outages.reacquisition_nis_mean);
}

/// The report's findings: the table, and for each group its members and the manoeuvre that
/// separates them.
void findings_md(std::ostream& md, const Diagnosis& d) {
  const tools::DiagnosisResult& r = d.r;
  const std::vector<tools::Separation>& seps = d.seps;
  const std::vector<tools::SeparationTrial>& trials = d.trials;
  md << "## Findings\n\n";
  if (r.findings.empty()) {
    md << "None: the baseline model explains the data.\n\n";
    return;
  }
  md << "| effect | component | estimate | sigma | unit | 95% interval | the filter's own estimate | z^2 | p | not separable from |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const tools::Finding& f : r.findings) {
    std::string cw;
    for (const auto& c : f.confounded_with) cw += (cw.empty() ? "" : ", ") + c.first + " (rho " + fmt("%.2f", c.second) + ")";
    md << "| " << fsw::effect_info(f.effect).name << " | " << f.component << " | "
       << (f.separable() ? fmt("%.4g", f.estimate) + (f.estimate_method == "profile_maximum" ? " (profile maximum)" : "")
                         : "group, below")
       << " | " << (f.separable() ? fmt("%.3g", f.sigma) : "") << " | " << f.unit << " | " << interval_cell(f.interval)
       << " | " << (f.separable() ? fmt("%.4g", f.filter_estimate) + " +- " + fmt("%.3g", f.filter_sigma) : "") << " | "
       << fmt("%.1f", f.z2)
       << (f.dof > 1 ? " (" + std::to_string(f.dof) + " dof)" : "")
       << " | " << fmt("%.2g", f.p_value) << " | " << cw << " |\n";
  }
  md << "\n";
  bool disagree = false;
  for (const tools::Finding& f : r.findings) {
    disagree = disagree || !f.interval.model_agrees;
    for (const tools::GroupMember& m : f.group) disagree = disagree || !m.alone_interval.model_agrees;
  }
  if (disagree)
    md << "**Not calibrated** (marked above): the filter's estimate lies where the profile likelihood's deviance "
          "is above "
       << fmt("%.2f", tools::kModelAgreementDeviance)
       << " (p < 0.001). The filter and the profile then disagree about the component, so the model does not "
          "describe its effect on these data (an unmodelled effect, a wrong noise model), and the interval, which "
          "assumes it does, is not a calibrated 95% statement (docs/diagnosis-intervals.md).\n\n";
  for (const tools::Finding& f : r.findings) {
    if (f.separable()) continue;
    md << "**A group, not one cause.** The data fit each of these alone about equally well and cannot tell them "
          "apart; the finding is the group. Each member's estimate is what it alone would need; plausibility is "
          "relative, under the members' priors only.\n\n"
          "| member | alone estimate | the filter's alone estimate, sigma | unit | alone 95% interval | prior sigmas | plausibility | correlation with the lead |\n"
          "|---|---|---|---|---|---|---|---|\n";
    for (const tools::GroupMember& m : f.group)
      md << "| " << m.name << " | "
         << (m.alone_interval.is_profile() ? fmt("%.4g", m.alone_interval.estimate) + " (profile maximum)" : fmt("%.4g", m.alone_estimate))
         << " | " << fmt("%.4g", m.alone_estimate) << " +- " << fmt("%.3g", m.alone_sigma) << " | " << m.unit
         << " | " << interval_cell(m.alone_interval) << " | " << fmt("%+.1f", m.prior_z) << " | " << fmt("%.2f", m.plausibility) << " | "
         << fmt("%+.4f", m.correlation) << " |\n";
    md << "\n";
    const std::size_t fi = static_cast<std::size_t>(&f - r.findings.data());
    const tools::Separation& sp = seps[fi];
    md << "**The manoeuvre that separates them.** ";
    if (sp.predicted) {
      const std::string file = "separation-" + std::to_string(fi + 1) + ".toml";
      md << "Fly on with *" << sp.label << "* (" << fmt("%.0f", sp.added_s) << " s more): the members' "
         << "correlation goes from " << fmt("%.4f", sp.flown_correlation) << " to " << fmt("%.3f", sp.predicted_correlation)
         << " predicted, " << (sp.separates ? "below" : "**not** below") << " the " << fmt("%.2f", sp.max_correlation)
         << " at which members are not told apart. " << sp.note << ".";
      if (!sp.scenario_toml.empty()) md << " The whole scenario: [" << file << "](" << file << ").";
      md << "\n\n| appended | more flight [s] | predicted correlation |\n|---|---|---|\n";
      for (const tools::SeparationTrial& t : trials)
        md << "| " << t.label << " | " << fmt("%.0f", t.added_s) << " | "
           << (t.evaluated && fi < t.correlation.size() ? fmt("%.3f", t.correlation[fi]) : "(" + t.error + ")")
           << " |\n";
      md << "\n";
    } else {
      md << sp.note << ". Fly: " << sp.label << ".\n\n";
    }
    md << "```toml\n" << sp.segments_toml << "```\n\n";
  }
}

/// The report's gain table: baseline against extended model.
void gain_md(std::ostream& md, const Diagnosis& d) {
  const tools::DiagnosisConfig& cfg = d.cfg;
  const tools::DiagnosisResult& r = d.r;
  const bool pvt = cfg.gnss_source == cfg::GnssSource::kPvt;
  md << "## Gain (extended model " << d.ext_name << ")\n\n| | baseline | extended |\n|---|---|---|\n";
  md << "| NIS per measurement | " << fmt("%.3f", r.base.innovations.nis_mean) << " | "
     << fmt("%.3f", r.extended.innovations.nis_mean) << " |\n";
  md << "| " << (pvt ? "position" : "pseudorange") << " innovation RMS [m] | "
     << fmt("%.3f", rms(r.base.innovations, pvt)) << " | " << fmt("%.3f", rms(r.extended.innovations, pvt)) << " |\n";
  md << "| " << (pvt ? "velocity" : "pseudorange-rate") << " innovation RMS [m/s] | "
     << fmt("%.4f", rms_rate(r.base.innovations, pvt)) << " | " << fmt("%.4f", rms_rate(r.extended.innovations, pvt)) << " |\n";
  md << "| log-likelihood (common measurements) | " << fmt("%.1f", r.base.innovations.log_likelihood) << " | "
     << fmt("%.1f", r.extended.innovations.log_likelihood) << " |\n";
  if (r.base.nav.available) {
    md << "| position RMS [m] | " << fmt("%.2f", r.base.nav.pos_rms_m) << " | " << fmt("%.2f", r.extended.nav.pos_rms_m) << " |\n";
    md << "| velocity RMS [m/s] | " << fmt("%.3f", r.base.nav.vel_rms_mps) << " | " << fmt("%.3f", r.extended.nav.vel_rms_mps) << " |\n";
    if (r.base.nav.attitude_samples > 0) {  // a reference without attitude scores position and velocity only
      md << "| tilt RMS [deg] | " << fmt("%.4f", r.base.nav.tilt_rms_deg) << " | " << fmt("%.4f", r.extended.nav.tilt_rms_deg) << " |\n";
      md << "| heading RMS [deg] | " << fmt("%.4f", r.base.nav.heading_rms_deg) << " | " << fmt("%.4f", r.extended.nav.heading_rms_deg) << " |\n";
    }
  }
  if (r.base.outages.windows > 0) {
    md << "| horizontal error after " << fmt("%.0f", cfg.outage_length_s) << " s GNSS outages, RMS of "
       << r.base.outages.windows << " [m] | " << fmt("%.2f", r.base.outages.horizontal_rms_m) << " | "
       << fmt("%.2f", r.extended.outages.horizontal_rms_m) << " |\n";
    md << "| ... max [m] | " << fmt("%.2f", r.base.outages.horizontal_max_m) << " | "
       << fmt("%.2f", r.extended.outages.horizontal_max_m) << " |\n";
    md << "| ... the filter's own 1-sigma there, RMS [m] | " << fmt("%.2f", r.base.outages.predicted_horizontal_rms_m)
       << " | " << fmt("%.2f", r.extended.outages.predicted_horizontal_rms_m) << " |\n";
    md << "| ... horizontal NEES, mean (2 if consistent) | " << fmt("%.1f", r.base.outages.horizontal_nees_mean)
       << " | " << fmt("%.1f", r.extended.outages.horizontal_nees_mean) << " |\n";
  }
  if (r.base.outages.reacquisitions > 0)
    md << "| NIS per scalar of the first update after each of " << r.base.outages.reacquisitions
       << " outages (1 if consistent; no reference needed) | " << fmt("%.1f", r.base.outages.reacquisition_nis_mean)
       << " | " << fmt("%.1f", r.extended.outages.reacquisition_nis_mean) << " |\n";
  md << "\n";
}

/// --report: the traces, the separation scenarios, the JSON, the plots and report.md. Returns
/// whether the plots were made.
bool write_report(const Diagnosis& d, const nlohmann::json& j) {
  const tools::DiagnosisConfig& cfg = d.cfg;
  const tools::DiagnosisResult& r = d.r;
  const std::vector<tools::Separation>& seps = d.seps;
  const auto& cands = tools::diagnosis_candidates();
  tools::RunDirectory run_dir(diagnose_opt.report);  // docs/faults.md: summary.json removed now, written last
  write_traces(run_dir.path("baseline.csv"), r.base);
  write_traces(run_dir.path("extended.csv"), r.extended);
  std::vector<std::string> files = {"diagnosis.json", "report.md", "baseline.csv", "extended.csv"};
  for (std::size_t fi = 0; fi < seps.size(); ++fi) {
    if (seps[fi].scenario_toml.empty()) continue;
    const std::string file = "separation-" + std::to_string(fi + 1) + ".toml";
    tools::write_text_file(run_dir.path(file), seps[fi].scenario_toml);
    files.push_back(file);
  }
  tools::write_json_file(run_dir.path("diagnosis.json"), j);
  const int rc = run_plot_script("plot_diagnosis.py", "'" + diagnose_opt.report + "'");
  tools::TextOutput md_out(run_dir.path("report.md"));
  std::ostream& md = md_out.os();
  md << "# Diagnosis of `" << diagnose_opt.log << "`\n\n";
  md << "Data: " << d.load_report << ".\n\n";
  md << "Baseline model: " << diagnose_opt.baseline << " states (+ clock, + Gauss-Markov GPS errors). Each of the "
     << cands.size() << " catalogue components was tried as one extra state; " << r.tested
     << " are observable with this data (posterior variance <= " << cfg.max_variance_ratio
     << " x prior); the test is Wald chi-square(1) at a family-wise false-alarm rate of " << cfg.alpha
     << " (threshold z^2 = " << fmt("%.2f", r.threshold_z2) << ").\n\n";
  if (d.chained) chain_md(md, d.chain);
  findings_md(md, d);
  evidence_md(md, d.evidence);
  if (!r.unobservable.empty()) {
    md << "Not observable with this data (never named as a cause): ";
    for (std::size_t k = 0; k < r.unobservable.size(); ++k) md << (k ? ", " : "") << r.unobservable[k];
    md << ".\n\n";
  }
  gain_md(md, d);
  if (rc == 0) {
    md << "![innovations](innovations.png)\n\n";
    if (r.base.nav.available) md << "![heading error](heading.png)\n\n";
    if (!r.extended_model.empty()) md << "![estimates](estimates.png)\n\n";  // the last search's states
  } else {
    md << "(plots not made: plot_diagnosis.py failed)\n\n";
  }
  md_out.commit();
  run_dir.finish({{"command", "diagnose"},
                  {"log", diagnose_opt.log},
                  {"complete", true},
                  {"findings", r.findings.size()},
                  {"plots", rc == 0},
                  {"files", files}});
  std::printf("report: %s/report.md\n", diagnose_opt.report.c_str());
  return rc == 0;
}

}  // namespace

int run_diagnose() {
  tools::require_distinct({diagnose_opt.json, diagnose_opt.report}, {diagnose_opt.log, diagnose_opt.flight_config});
  const tools::InterruptPolling polling;
  Diagnosis d;
  load(d);
  search(d);
  d.profiles = profile_components(d);
  separate_groups(d);
  check_evidence_and_name_model(d);
  const nlohmann::json j = diagnosis_json(d);
  tools::write_json_file(diagnose_opt.json, j);
  print_summary(d);
  bool plots_failed = false;
  if (!diagnose_opt.report.empty()) plots_failed = !write_report(d, j);
  if (plots_failed) {  // docs/faults.md: an output not written fails the command; the rest is complete
    std::fprintf(stderr, "sdins diagnose: error: the report's figures could not be made (plot_diagnosis.py's message "
                         "above); the JSON and report.md are complete\n");
    return 1;
  }
  return 0;
}

}  // namespace sdins
