// sdins fly: free-inertial (unaided) flight of a scenario through the fsw mechanization with the
// scenario's IMU errors; prints the error growth and optionally writes a CSV.
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include "commands.hpp"
#include "sim/imu_model.hpp"
#include "sim/trajectory.hpp"
#include "cfg/flight_config.hpp"
#include "tools/free_inertial.hpp"
#include "tools/output_file.hpp"

namespace sdins {
namespace {
struct FlyOptions {
  ScenarioOptions scenario;
  std::string errors;
  std::string csv;
} fly_opt;
}  // namespace

void register_fly(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "fly", "Free-inertial flight of a scenario: truth simulator -> IMU error model -> fsw mechanization at the "
             "navigation rate of config/default.toml (200 Hz), no aiding. Prints position/velocity/attitude error "
             "against truth every 60 s.");
  add_scenario_options(sub, fly_opt.scenario);
  sub->add_option("--errors", fly_opt.errors, "override the IMU error set (default: the scenario's)")->check(CLI::IsMember({"paper", "baseline", "none"}));
  sub->add_option("--csv", fly_opt.csv, "write the 1 Hz error history to this CSV file");
}

int run_fly() {
  sim::Scenario sc = fly_opt.scenario.load();
  if (fly_opt.errors == "paper") sc.imu.errors = sim::ImuErrorSet::kPaper;
  if (fly_opt.errors == "baseline") sc.imu.errors = sim::ImuErrorSet::kBaseline;
  if (fly_opt.errors == "none") sc.imu.errors = sim::ImuErrorSet::kNone;
  std::string err;
  auto motion = sim::FlightMotion::create(sc, err);
  if (!motion) throw std::runtime_error(err);
  sim::ImuModel imu(sim::draw_imu_errors(sc.imu, sc.effects, sc.seed), sc.seed);
  // docs/faults.md: the CSV goes to a temporary file renamed into place when complete.
  std::optional<tools::TextOutput> csv_out;
  if (!fly_opt.csv.empty()) {
    tools::require_distinct({fly_opt.csv}, {fly_opt.scenario.file});
    csv_out.emplace(fly_opt.csv);
    csv_out->os() << "t_s,dpos_E_m,dpos_N_m,dpos_U_m,dvel_E_mps,dvel_N_mps,dvel_U_mps,phi_E_arcsec,phi_N_arcsec,phi_U_arcsec\n";
  }
  tools::FreeInertialConfig cfg;
  cfg.duration_s = sc.duration_s;
  cfg.imu_rate_hz = sc.imu.rate_hz;
  cfg.nav_rate_hz = cfg::shipped_flight_config().app.exec.nav_rate_hz;  // config/default.toml
  cfg.truth_thread = true;  // one flight: its truth beside it (the same samples)
  const int frames_per_s = static_cast<int>(std::lround(cfg.nav_rate_hz));
  std::printf("%8s %10s %10s %12s %12s %12s\n", "t [s]", "horiz [m]", "vert [m]", "phi_E [\"]", "phi_N [\"]",
              "phi_U [\"]");
  int frame = 0;
  fsw::Status st = fsw::Status::kOk;
  tools::run_free_inertial(
      *motion, &imu, cfg,
      [&](const sim::TruthSample& truth, const fsw::NavState& nav) {
        ++frame;
        if (frame % frames_per_s != 0) return;
        const tools::NavErrors e = tools::nav_errors(nav, truth);
        const fsw::Vec3 phi = e.att_phi_enu_rad * fsw::kRadToArcsec;
        if (csv_out) {
          csv_out->os() << truth.t_s << "," << e.pos_enu_m.x() << "," << e.pos_enu_m.y() << "," << e.pos_enu_m.z() << ","
              << e.vel_enu_mps.x() << "," << e.vel_enu_mps.y() << "," << e.vel_enu_mps.z() << "," << phi.x() << ","
              << phi.y() << "," << phi.z() << "\n";
        }
        if (frame % (frames_per_s * 60) == 0) {
          std::printf("%8.0f %10.2f %10.2f %12.3f %12.3f %12.3f\n", truth.t_s, e.pos_enu_m.head<2>().norm(),
                      e.pos_enu_m.z(), phi.x(), phi.y(), phi.z());
        }
      },
      &st);
  if (st != fsw::Status::kOk) throw std::runtime_error(std::string("fsw step failed: ") + fsw::to_string(st));
  if (csv_out) csv_out->commit();
  return 0;
}

}  // namespace sdins
