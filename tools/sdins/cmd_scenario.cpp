// sdins scenario: validate a scenario file and show the flight timeline it produces.
#include <cstdio>
#include <stdexcept>

#include "commands.hpp"
#include "sim/trajectory.hpp"

namespace sdins {
namespace {
struct ScenarioCheckOptions {
  std::string file;
} scenario_opt;
}  // namespace

void register_scenario(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "scenario", "Check a scenario TOML file (unknown keys and bad values are reported with their line) and print "
                  "the flight timeline it produces. Without FILE: the built-in bank-to-turn scenario.");
  sub->add_option("file", scenario_opt.file, "scenario TOML file (default: the built-in bank-to-turn scenario)");
}

int run_scenario_check() {
  const sim::Scenario sc = ScenarioOptions{scenario_opt.file}.load();
  std::string err;
  auto motion = sim::FlightMotion::create(sc, err);
  if (!motion) throw std::runtime_error(err);
  std::printf("scenario '%s': %.1f s, seed %llu, start %.4f N %.4f E %.0f m, %.1f m/s, heading %.1f deg\n",
              sc.name.c_str(), sc.duration_s, static_cast<unsigned long long>(sc.seed), sc.start.lat_deg,
              sc.start.lon_deg, sc.start.alt_m, sc.start.speed_mps, sc.start.heading_deg);
  int turns = 0, manoeuvres = 0, last_segment = -2;
  double turning_s = 0.0;
  for (const auto& p : motion->timeline()) {
    if (p.t0_s >= sc.duration_s) break;
    const double t1 = std::min(p.t1_s, sc.duration_s);
    if (p.turn >= 0) turning_s += t1 - p.t0_s;
    if (p.turn >= 0 && p.kind == sim::FlightPhase::Kind::kRollIn) ++turns;
    if (p.segment >= 0 && p.segment != last_segment) {
      const sim::Segment& s = sc.segments[static_cast<std::size_t>(p.segment)];
      if (s.type != sim::SegmentType::kStraight && s.type != sim::SegmentType::kTurn) ++manoeuvres;
    }
    last_segment = p.segment;
  }
  std::printf("timeline: %d turns started, %.1f s turning, %.1f s otherwise; %d other manoeuvres (speed changes, "
              "climbs, rolls without turning); IMU %d Hz, errors %s\n",
              turns, turning_s, sc.duration_s - turning_s, manoeuvres, sc.imu.rate_hz,
              sc.imu.errors == sim::ImuErrorSet::kPaper      ? "paper"
              : sc.imu.errors == sim::ImuErrorSet::kBaseline ? "baseline"
                                                             : "none");
  for (std::size_t e = 0; e < fsw::kEffectCount; ++e) {
    const auto& info = fsw::kEffectCatalogue[e];
    if (!sc.effects.on(info.effect)) continue;
    std::printf("effect %s:", info.name);
    for (std::size_t k = 0; k < info.n_components; ++k) {
      std::printf(" %s%s%g", info.components[k], info.components[k][0] ? "=" : "", sc.effects.get(info.effect, k));
    }
    std::printf(" %s\n", info.unit);
  }
  return 0;
}

}  // namespace sdins
