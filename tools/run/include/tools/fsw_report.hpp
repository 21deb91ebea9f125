// The end-of-run summary of a flight-software node as JSON (`sdins sil/fsw/replay --json`), one
// format for every way of running the flight software (fields documented in docs/running.md).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "hal/can_rx_assembler.hpp"
#include "hal/fsw_node.hpp"

namespace tools {

/// initialised, init_t_s, nav_frames, digest (16 hex digits), last_nav {t_s, lat_deg, lon_deg,
/// height_m, vel_enu_mps}, app (flight app counters), executive (executive and EKF health),
/// telemetry (network: the run published to the LCM network, network_given_up, url, published,
/// logged, send/log failures).
nlohmann::json fsw_summary_json(const hal::FswNode& node);
/// The parts of it, for summaries that hold copies rather than the node (tools/hil.hpp).
nlohmann::json last_nav_json(const fsw::NavState& n);
nlohmann::json app_json(const fsw::FlightAppHealth& a);
nlohmann::json executive_json(const fsw::ExecutiveHealth& e);
/// Every CAN receive counter by name.
nlohmann::json can_rx_json(const hal::CanRxHealth& h);
/// The digest as 16 lower-case hex digits.
std::string digest_hex(std::uint64_t d);
/// The telemetry line's network part: the URL the run published to (and whether it was given up
/// after failed sends), or why it published to none.
std::string telemetry_network_text(const hal::LcmTelemetry& tel);
/// Prints the summary's key lines to stdout.
void print_fsw_summary(const hal::FswNode& node);
/// A WARNING line per configuration mismatch the counters show (frame_rate_mismatch), none when clean.
void print_configuration_warnings(const fsw::ExecutiveHealth& e);

}  // namespace tools
