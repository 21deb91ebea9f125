// Every field of fsw::FlightAppConfig (fsw/flight_app_config.hpp), listed once beside it:
// X(path, in_schema). in_schema false: set by the flight application or a harness, not by a file
// (FlightApp replaces the EKF's initial sigmas by init_*; the diagnosis sets the extension sigmas
// per run). Used by the test that config/default.toml sets every key
// (tests/unit/test_flight_config.cpp, which also pins the structs' sizes so that an added field
// must be listed), by the generator of the bare-metal image's configuration
// (cfg/gen/gen_baremetal_config.cpp) and by the configuration's encoding for the target replay
// (fsw/flight_app_config_wire.hpp).
#pragma once

#define FLIGHT_CONFIG_FIELDS(X)                                                                       \
  X(exec.imu_samples_per_frame, true) X(exec.nav_rate_hz, true) X(exec.frames_per_ekf, true)          \
  X(exec.gnss_wait_frames, true) X(exec.max_gnss_age_s, true) X(exec.frame_budget_s, true)            \
  X(exec.ekf_latency_frames, true) X(exec.ekf_group_inline, false)                                    \
  X(exec.ekf.pos_sigma_m, false) X(exec.ekf.vel_sigma_mps, false) X(exec.ekf.att_sigma_rad, false)    \
  X(exec.ekf.accel_bias_sigma_mps2, true) X(exec.ekf.gyro_bias_sigma_radps, true)                    \
  X(exec.ekf.accel_misalign_sigma_rad, true) X(exec.ekf.gyro_misalign_sigma_rad, true)               \
  X(exec.ekf.accel_scale_sigma, true) X(exec.ekf.gyro_scale_sigma, true)                             \
  X(exec.ekf.gyro_g_sens_sigma_radps_per_mps2, false) X(exec.ekf.time_offset_sigma_s, false)         \
  X(exec.ekf.time_drift_sigma_sps, false) X(exec.ekf.lever_arm_sigma_m, false)                       \
  X(exec.ekf.tropo_scale_sigma, false) X(exec.ekf.iono_scale_sigma, false)                           \
  X(exec.ekf.frozen_states, false) X(exec.ekf.clock_bias_sigma_m, true)                              \
  X(exec.ekf.clock_drift_sigma_mps, true) X(exec.ekf.vrw_mps_per_rts, true)                          \
  X(exec.ekf.arw_rad_per_rts, true) X(exec.ekf.accel_bias_rw_mps2_per_rts, true)                     \
  X(exec.ekf.gyro_bias_rw_radps_per_rts, true) X(exec.ekf.clock_bias_psd_m2ps, true)                 \
  X(exec.ekf.clock_drift_psd_m2ps3, true) X(exec.ekf.pseudorange_sigma_m, true)                      \
  X(exec.ekf.pseudorange_rate_sigma_mps, true) X(exec.ekf.range_gm_sigma_m, true)                    \
  X(exec.ekf.range_gm_tau_s, true) X(exec.ekf.range_rate_gm_sigma_mps, true)                         \
  X(exec.ekf.range_rate_gm_tau_s, true) X(exec.ekf.use_pseudorange_rate, true)                       \
  X(exec.ekf.gate_chi2, true) X(exec.ekf.pvt_pos_sigma_floor_m, true)                                \
  X(exec.ekf.pvt_vel_sigma_floor_mps, true) X(exec.ekf.pvt_sigma_scale, true)                        \
  X(exec.ekf.lever_arm_b_m, true) X(exec.ekf.propagation_substep_frames, true)                       \
  X(exec.ekf.nis_window, true) X(exec.ekf.runaway_epochs, true) X(min_satellites_for_init, true)     \
  X(max_init_pdop, true) X(min_init_speed_mps, true) X(levelling_samples, true)                      \
  X(init_pos_sigma_m, true) X(init_vel_sigma_mps, true) X(init_att_sigma_rad, true)                  \
  X(init_heading_offset_rad, true) X(pvt_max_quality, true) X(init_mode, true) X(alignment_s, true)  \
  X(static_max_speed_mps, true) X(static_max_rate_dev_radps, true) X(static_max_accel_dev_mps2, true) \
  X(vm_min_s, true) X(vm_max_s, true) X(vm_max_heading_sigma_rad, true) X(vm_rest_gyro_bias, true)   \
  X(vm_rest_min_s, true)

