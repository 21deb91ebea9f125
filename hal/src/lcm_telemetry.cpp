#include "hal/lcm_telemetry.hpp"

#include <lcm/lcm.h>

#include <cstdio>
#include <cstdlib>

namespace hal {
namespace {
void stderr_warning(const char* message, void*) { std::fprintf(stderr, "sdins: warning: %s\n", message); }
}  // namespace

std::string resolve_lcm_url(const std::string& requested) {
  if (!requested.empty()) return requested;
  const char* env = std::getenv("LCM_DEFAULT_URL");
  if (env != nullptr && env[0] != '\0') return env;
  return kLcmDefaultUrl;
}

LcmTelemetry::LcmTelemetry() : warn_fn_(stderr_warning) {}

LcmTelemetry::~LcmTelemetry() {
  // docs/faults.md: a log not closed (an exception, an early return) is dropped, never put in place half
  // written.
  abort_log();
  close();
}

void LcmTelemetry::set_warning_handler(WarningHandler fn, void* user) {
  warn_fn_ = fn != nullptr ? fn : stderr_warning;
  warn_user_ = user;
}

void LcmTelemetry::warn(const std::string& message) { warn_fn_(message.c_str(), warn_user_); }

LcmLogStatus LcmTelemetry::open(const LcmTelemetryConfig& cfg) {
  close();
  max_failures_ = cfg.max_consecutive_send_failures > 0 ? cfg.max_consecutive_send_failures : 1;
  consecutive_failures_ = 0;
  published_ = 0;
  send_failures_ = 0;
  warned_log_ = false;
  network_used_ = false;
  network_given_up_ = false;
  if (!cfg.log_path.empty()) {
    const LcmLogStatus st = log_.open(cfg.log_path);
    if (st != LcmLogStatus::kOk) return st;
  }
  url_ = resolve_lcm_url(cfg.lcm_url);
  if (url_ == "none") return LcmLogStatus::kOk;
  lcm_ = lcm_create(url_.c_str());
  network_used_ = lcm_ != nullptr;
  if (lcm_ == nullptr) {
    warn("LCM telemetry: cannot create '" + url_ + "' (LCM needs a multicast route; on an isolated loopback: " +
         "ip route add 224.0.0.0/4 dev lo); continuing " + (log_active() ? "with the log file only" : "without telemetry"));
  }
  return LcmLogStatus::kOk;
}

LcmLogStatus LcmTelemetry::publish(const char* channel, const void* data, std::size_t len, std::int64_t timestamp_us) {
  if (channel == nullptr || !lcm_channel_name_ok(channel)) return LcmLogStatus::kBadChannel;
  LcmLogStatus result = LcmLogStatus::kOk;
  if (lcm_ != nullptr) {
    if (len <= 0x7fffffffu && lcm_publish(lcm_, channel, data, static_cast<unsigned int>(len)) == 0) {
      ++published_;
      consecutive_failures_ = 0;
    } else {
      ++send_failures_;
      if (++consecutive_failures_ >= max_failures_) {
        warn("LCM telemetry: " + std::to_string(consecutive_failures_) + " sends in a row failed on '" + url_ +
             "'; giving up the network and continuing " + (log_active() ? "with the log file only" : "without telemetry"));
        lcm_destroy(lcm_);
        lcm_ = nullptr;
        network_given_up_ = true;
      }
    }
  }
  if (log_.is_open()) {
    const LcmLogStatus st = log_.write(channel, data, len, timestamp_us);
    if (st != LcmLogStatus::kOk) {
      if (!warned_log_) {
        warn("LCM log '" + log_.path() + "': write failed (" + to_string(st) + "); later failures are only counted");
        warned_log_ = true;
      }
      result = st;
    }
  }
  return result;
}

LcmLogStatus LcmTelemetry::close() {
  if (lcm_ != nullptr) lcm_destroy(lcm_);
  lcm_ = nullptr;
  return log_.close();
}

}  // namespace hal
