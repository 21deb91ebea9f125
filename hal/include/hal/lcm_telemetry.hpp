// LCM telemetry: publishes already-encoded messages on UDP multicast (LCM "udpm") and/or writes
// them to an LCM log.
//
// URL: LcmTelemetryConfig::lcm_url (the commands' --lcm-url); when empty, the environment's
// LCM_DEFAULT_URL; when that is unset, kLcmDefaultUrl = udpm://239.255.76.67:7667?ttl=0 (LCM's own
// default group and port; ttl=0 keeps every packet on this host). "none" turns the network off.
//
// Fallback: when the udpm instance cannot be created (LCM needs a multicast route: on a host
// whose only interface is an isolated loopback, `ip route add 224.0.0.0/4 dev lo` as root), or
// sends keep failing (max_consecutive_send_failures in a row), it warns once and continues
// log-only; a run is never stopped by the network. Publishing copies no message: the caller
// passes the bytes it encoded into its own buffer (LcmLogSink does that), and the raw lcm_publish
// C call is used, so the typed lcm::LCM::publish (which allocates) is never involved.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "hal/lcm_channels.hpp"
#include "hal/lcm_log.hpp"

typedef struct _lcm_t lcm_t;  // NOLINT: LCM's C handle (lcm/lcm.h)

namespace hal {

struct LcmTelemetryConfig {
  std::string lcm_url;   ///< "": $LCM_DEFAULT_URL, else kLcmDefaultUrl; "none": no network output
  std::string log_path;  ///< "": no log file
  int max_consecutive_send_failures = 50;  ///< then the network is given up (log-only)
};

/// The URL an empty --lcm-url stands for: $LCM_DEFAULT_URL if set and non-empty, else kLcmDefaultUrl.
std::string resolve_lcm_url(const std::string& requested);

class LcmTelemetry {
 public:
  /// Receives each warning once (default: "sdins: warning: ..." on stderr).
  using WarningHandler = void (*)(const char* message, void* user);

  LcmTelemetry();
  ~LcmTelemetry();
  LcmTelemetry(const LcmTelemetry&) = delete;
  LcmTelemetry& operator=(const LcmTelemetry&) = delete;

  void set_warning_handler(WarningHandler fn, void* user);

  /// Opens the log (kOpenFailed when it cannot be created: a requested log is not optional) and
  /// the network (never fails: without it the telemetry is log-only, with one warning).
  LcmLogStatus open(const LcmTelemetryConfig& cfg);
  /// Publishes and/or logs one encoded message. timestamp_us is the log event's timestamp.
  /// kOk unless the log write failed (kWriteFailed) or the channel name is bad (kBadChannel);
  /// network failures are counted and handled by the fallback, never returned.
  LcmLogStatus publish(const char* channel, const void* data, std::size_t len, std::int64_t timestamp_us);
  /// Flushes and closes the log, destroys the LCM instance. kWriteFailed if the log's final flush failed.
  LcmLogStatus close();
  /// Drops the log file being written (its target keeps its old contents).
  void abort_log() { log_.abort(); }

  /// The network instance is open now (false after close() and once the network was given up).
  bool network_active() const { return lcm_ != nullptr; }
  /// The run's telemetry went to the network: open() created the LCM instance. Stays true after
  /// close(), for the end-of-run report (network_active() alone said "off" there, after the
  /// node's close, although every message had been sent).
  bool network_used() const { return network_used_; }
  /// The network was given up after max_consecutive_send_failures failed sends in a row.
  bool network_given_up() const { return network_given_up_; }
  bool log_active() const { return log_.is_open(); }
  /// The URL in use (after resolve_lcm_url), or "none".
  const std::string& url() const { return url_; }
  std::uint64_t published() const { return published_; }
  std::uint64_t send_failures() const { return send_failures_; }
  std::uint64_t logged() const { return log_.events_written(); }
  std::uint64_t log_failures() const { return log_.write_failures(); }
  const LcmLogWriter& log() const { return log_; }

 private:
  void warn(const std::string& message);

  lcm_t* lcm_ = nullptr;
  LcmLogWriter log_;
  std::string url_;
  int max_failures_ = 50;
  int consecutive_failures_ = 0;
  std::uint64_t published_ = 0;
  std::uint64_t send_failures_ = 0;
  bool warned_log_ = false;
  bool network_used_ = false;
  bool network_given_up_ = false;
  WarningHandler warn_fn_ = nullptr;
  void* warn_user_ = nullptr;
};

}  // namespace hal
