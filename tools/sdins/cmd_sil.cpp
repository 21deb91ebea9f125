// sdins sil: software in the loop. The truth simulator's sensors go through the CAN codec and the
// receive assembler in-process (the same frames and the same decoding as a HIL run over a bus)
// into the flight-software node, which publishes the same LCM telemetry and writes the same log.
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "commands.hpp"
#include "fsw/driver.hpp"
#include "hal/can_fsw_input.hpp"
#include "hal/can_protocol.hpp"
#include "tools/free_inertial.hpp"
#include "tools/fsw_report.hpp"
#include "tools/output_file.hpp"
#include "tools/step_producer.hpp"
#include "sim/sensor_stream.hpp"

namespace sdins {
namespace {
struct SilOptions {
  ScenarioOptions scenario;
  FswRunOptions run;
} sil_opt;
}  // namespace

void register_sil(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "sil", "Software in the loop: simulator -> CAN frames (in-process) -> flight software (in-motion init, 1 Hz "
             "EKF, 200 Hz mechanization) -> LCM telemetry and log. Same frames and outputs as a lockstep HIL run.");
  add_scenario_options(sub, sil_opt.scenario);
  add_fsw_run_options(sub, sil_opt.run, "");
}

int run_sil() {
  tools::require_distinct({sil_opt.run.log, sil_opt.run.json}, {sil_opt.scenario.file, sil_opt.run.flight_config});
  const sim::Scenario sc = sil_opt.scenario.load();
  const hal::FswNodeConfig cfg = sil_opt.run.node_config();  // validated at load, before the flight is simulated
  // The truth, the sensor models and the encoding on one thread of their own (StepProducer below,
  // the truth generated alongside: no memory that grows with the duration), the receive side and
  // the flight software on this one: the two halves of a SIL run's time.
  sim::SensorStream stream(sc, sc.seed);
  hal::FswNode node;
  std::string err;
  if (!node.open(cfg, err)) throw std::runtime_error(err);
  hal::CanFswInput input(node.summary());
  std::uint64_t n_frames = 0;
  int encode_rejected = 0;
  sim::TruthSample truth;  // the last sample's
  {
    // A few GPS intervals ahead; the same frames in the same order as encoded here
    // (tools/step_producer.hpp).
    tools::StepProducer producer(stream, nullptr);
    tools::EncodedStep step;
    while (producer.next(step)) {
      encode_rejected += step.r.imu_rejected + step.r.gps_rejected + step.r.almanac_rejected;
      // Receive time: the simulation time at the end of the step (the GPS epoch timeout runs on it).
      for (const hal::CanFrame& f : step.frames) {
        input.push(f, step.truth_t_s);
        fsw::drive(input, node);
      }
      n_frames += step.frames.size();
      if (step.has_full_truth) {
        node.on_truth(step.full_truth.t_s, step.full_truth.llh, step.full_truth.vel_enu_mps, step.full_truth.C_b_n);
        truth = step.full_truth;
      }
    }
    if (!producer.error().empty()) throw std::runtime_error("simulator: " + producer.error());
  }
  input.finish();
  fsw::drive(input, node);
  if (!node.close(err)) throw std::runtime_error(err);

  std::printf("sil: %s, %.0f s, seed %llu, %s-state model; %llu CAN frames (%d not encodable), %u rejected on receive\n",
              sc.name.c_str(), sc.duration_s, static_cast<unsigned long long>(sc.seed), sil_opt.run.model.c_str(),
              static_cast<unsigned long long>(n_frames), encode_rejected, input.health().rejections());
  tools::print_fsw_summary(node);
  nlohmann::json j = tools::fsw_summary_json(node);
  const fsw::NavState& nav = node.summary().last_nav;
  if (node.summary().initialised && std::abs(nav.t_s - truth.t_s) < 1e-6) {
    const tools::NavErrors e = tools::nav_errors(nav, truth);
    std::printf("final error vs truth: position %.2f m (E %.2f N %.2f U %.2f), velocity %.3f m/s, attitude E/N/U "
                "%.4f %.4f %.4f deg\n",
                e.pos_enu_m.norm(), e.pos_enu_m.x(), e.pos_enu_m.y(), e.pos_enu_m.z(), e.vel_enu_mps.norm(),
                e.att_phi_enu_rad.x() * fsw::kRadToDeg, e.att_phi_enu_rad.y() * fsw::kRadToDeg,
                e.att_phi_enu_rad.z() * fsw::kRadToDeg);
    j["final_error"] = {{"pos_enu_m", {e.pos_enu_m.x(), e.pos_enu_m.y(), e.pos_enu_m.z()}},
                        {"vel_enu_mps", {e.vel_enu_mps.x(), e.vel_enu_mps.y(), e.vel_enu_mps.z()}},
                        {"att_enu_deg",
                         {e.att_phi_enu_rad.x() * fsw::kRadToDeg, e.att_phi_enu_rad.y() * fsw::kRadToDeg,
                          e.att_phi_enu_rad.z() * fsw::kRadToDeg}}};
  }
  if (!sil_opt.run.json.empty()) {
    j["mode"] = "sil";
    j["model"] = sil_opt.run.model;
    j["scenario"] = sc.name;
    j["duration_s"] = sc.duration_s;
    j["seed"] = sc.seed;
    j["can_frames"] = n_frames;
    j["can_rx"] = tools::can_rx_json(input.health());
    tools::write_json_file(sil_opt.run.json, j);
  }
  return node.summary().initialised ? 0 : 2;
}

}  // namespace sdins
