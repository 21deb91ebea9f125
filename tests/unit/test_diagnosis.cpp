// The diagnosis (tools/diagnosis.hpp): hidden effects must be found, named and estimated; data
// with only what the baseline models must give no finding.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "sim/effects.hpp"
#include "tools/diagnosis.hpp"

namespace {

sim::Scenario baseline_scenario(double duration_s, std::uint64_t seed) {
  sim::Scenario sc;
  sc.duration_s = duration_s;
  sc.seed = seed;
  sc.imu.errors = sim::ImuErrorSet::kBaseline;
  return sc;
}

void print(const tools::DiagnosisResult& r) {
  const auto& cands = tools::diagnosis_candidates();
  std::printf("threshold %.2f tested %d\n", r.threshold_z2, r.tested);
  for (std::size_t c = 0; c < cands.size() && c < r.screening_z2.size(); ++c)
    std::printf("  %-28s z2 %8.2f ratio %6.3f\n", tools::candidate_name(cands[c]).c_str(), r.screening_z2[c],
                r.screening_ratio[c]);
  for (const auto& f : r.findings) {
    std::printf("FINDING %s.%s %.4g +- %.4g %s z2 %.1f\n", fsw::effect_info(f.effect).name, f.component.c_str(),
                f.estimate, f.sigma, f.unit.c_str(), f.z2);
    for (const auto& c : f.confounded_with) std::printf("   confounded %s %.3f\n", c.first.c_str(), c.second);
  }
  std::printf("base: nis %.3f pr %.3f prr %.4f ll %.1f n %d | pos %.2f vel %.3f tilt %.4f head %.4f\n",
              r.base.innovations.nis_mean, r.base.innovations.pr_rms_m, r.base.innovations.prr_rms_mps,
              r.base.innovations.log_likelihood, r.base.innovations.common, r.base.nav.pos_rms_m, r.base.nav.vel_rms_mps,
              r.base.nav.tilt_rms_deg, r.base.nav.heading_rms_deg);
  std::printf("ext : nis %.3f pr %.3f prr %.4f ll %.1f n %d | pos %.2f vel %.3f tilt %.4f head %.4f\n",
              r.extended.innovations.nis_mean, r.extended.innovations.pr_rms_m, r.extended.innovations.prr_rms_mps,
              r.extended.innovations.log_likelihood, r.extended.innovations.common, r.extended.nav.pos_rms_m,
              r.extended.nav.vel_rms_mps, r.extended.nav.tilt_rms_deg, r.extended.nav.heading_rms_deg);
}

TEST(DiagnosisExperiment, Explore) {
  const char* e = std::getenv("SDINS_DIAG_EXPLORE");
  if (e == nullptr) GTEST_SKIP() << "set SDINS_DIAG_EXPLORE=effect=value[,duration,seed]";
  std::string spec = e;
  double dur = 600;
  unsigned seed = 1;
  const char* d = std::getenv("SDINS_DIAG_DURATION");
  if (d) dur = std::atof(d);
  const char* s = std::getenv("SDINS_DIAG_SEED");
  if (s) seed = static_cast<unsigned>(std::atoi(s));
  sim::Scenario sc = baseline_scenario(dur, seed);
  if (spec != "none") {
    std::size_t pos = 0;
    while (pos < spec.size()) {
      std::size_t c = spec.find(',', pos);
      if (c == std::string::npos) c = spec.size();
      ASSERT_EQ(sim::apply_effect_assignment(sc.effects, spec.substr(pos, c - pos)), "");
      pos = c + 1;
    }
  }
  const tools::RecordedData data = tools::record_scenario(sc, seed);
  const tools::DiagnosisConfig cfg = tools::default_diagnosis_config();
  const tools::DiagnosisResult r =
      tools::diagnose(data, cfg, [](const std::string& m) { std::printf("%s\n", m.c_str()); });
  print(r);
}

}  // namespace
