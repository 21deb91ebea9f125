// Generated from config/default.toml by sdins_gen_baremetal_config (cfg/gen/gen_baremetal_config.cpp);
// do not edit. Regenerate after changing config/default.toml or fsw::FlightAppConfig:
//   cmake --build --preset release --target sdins_gen_baremetal_config
//   build/release/cfg/sdins_gen_baremetal_config config/default.toml > fsw/baremetal/default_flight_config.hpp
// Tests: BaremetalConfig.* (the values equal the file's), baremetal_config_generated (this file
// is what the generator writes now).
#pragma once

#include <cstdint>

#include "fsw/flight_app.hpp"

namespace sdins_baremetal {

/// The flight configuration of config/default.toml (every field, in the flight software's units).
inline fsw::FlightAppConfig default_flight_config() {
  fsw::FlightAppConfig c;
  c.exec.imu_samples_per_frame = 5;
  c.exec.nav_rate_hz = 200;
  c.exec.frames_per_ekf = 200;
  c.exec.gnss_wait_frames = 40;
  c.exec.max_gnss_age_s = 0.25;
  c.exec.frame_budget_s = 0.0050000000000000001;
  c.exec.ekf_latency_frames = 10;
  c.exec.ekf_group_inline = true;
  c.exec.ekf.pos_sigma_m = 10;
  c.exec.ekf.vel_sigma_mps = 0.5;
  c.exec.ekf.att_sigma_rad = fsw::Vec3(0.00048481368110953597, 0.00048481368110953597, 0.00048481368110953597);
  c.exec.ekf.accel_bias_sigma_mps2 = 0.00098066499999999992;
  c.exec.ekf.gyro_bias_sigma_radps = 4.8481368110953601e-08;
  c.exec.ekf.accel_misalign_sigma_rad = 2.4240684055476798e-05;
  c.exec.ekf.gyro_misalign_sigma_rad = 2.4240684055476798e-05;
  c.exec.ekf.accel_scale_sigma = 0.0001;
  c.exec.ekf.gyro_scale_sigma = 0.0001;
  c.exec.ekf.gyro_g_sens_sigma_radps_per_mps2 = 0;
  c.exec.ekf.time_offset_sigma_s = 0;
  c.exec.ekf.time_drift_sigma_sps = 0;
  c.exec.ekf.lever_arm_sigma_m = 0;
  c.exec.ekf.tropo_scale_sigma = 0;
  c.exec.ekf.iono_scale_sigma = 0;
  c.exec.ekf.frozen_states = UINT64_C(0);
  c.exec.ekf.clock_bias_sigma_m = 10;
  c.exec.ekf.clock_drift_sigma_mps = 0.5;
  c.exec.ekf.vrw_mps_per_rts = 0.0001;
  c.exec.ekf.arw_rad_per_rts = 1.9999999999999999e-07;
  c.exec.ekf.accel_bias_rw_mps2_per_rts = 0;
  c.exec.ekf.gyro_bias_rw_radps_per_rts = 0;
  c.exec.ekf.clock_bias_psd_m2ps = 0.0089875517873681757;
  c.exec.ekf.clock_drift_psd_m2ps3 = 0.035481432270250989;
  c.exec.ekf.pseudorange_sigma_m = 0.29999999999999999;
  c.exec.ekf.pseudorange_rate_sigma_mps = 0.01;
  c.exec.ekf.range_gm_sigma_m = 8;
  c.exec.ekf.range_gm_tau_s = 60;
  c.exec.ekf.range_rate_gm_sigma_mps = 0.20000000000000001;
  c.exec.ekf.range_rate_gm_tau_s = 10;
  c.exec.ekf.use_pseudorange_rate = true;
  c.exec.ekf.gate_chi2 = 10.83;
  c.exec.ekf.pvt_pos_sigma_floor_m = 0.02;
  c.exec.ekf.pvt_vel_sigma_floor_mps = 0.01;
  c.exec.ekf.pvt_sigma_scale = 1;
  c.exec.ekf.lever_arm_b_m = fsw::Vec3(0, 0, 0);
  c.exec.ekf.propagation_substep_frames = 10;
  c.exec.ekf.nis_window = 10;
  c.exec.ekf.runaway_epochs = 5;
  c.min_satellites_for_init = 5;
  c.max_init_pdop = 6;
  c.min_init_speed_mps = 20;
  c.levelling_samples = 200;
  c.init_pos_sigma_m = 30;
  c.init_vel_sigma_mps = 1;
  c.init_att_sigma_rad = fsw::Vec3(0.0034906585039886592, 0.0034906585039886592, 0.017453292519943295);
  c.init_heading_offset_rad = 0;
  c.pvt_max_quality = 6;
  c.init_mode = fsw::InitMode::kTrack;
  c.alignment_s = 60;
  c.static_max_speed_mps = 0.20000000000000001;
  c.static_max_rate_dev_radps = 0.0017453292519943296;
  c.static_max_accel_dev_mps2 = 0.10000000000000001;
  c.vm_min_s = 2;
  c.vm_max_s = 20;
  c.vm_max_heading_sigma_rad = 0.05235987755982989;
  c.vm_rest_gyro_bias = true;
  c.vm_rest_min_s = 1;
  return c;
}

}  // namespace sdins_baremetal
