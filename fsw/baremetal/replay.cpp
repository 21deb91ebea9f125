// The target replay (see replay.hpp): the same file in the QEMU image and in the host tool.
#include "replay.hpp"

#include "fsw/nav_digest.hpp"

#include <cmath>
#include <cstring>

#include "fsw/driver.hpp"
#include "fsw/flight_app.hpp"
#include "fsw/flight_app_config_wire.hpp"

namespace sdins_target {
namespace {

std::uint32_t offset_of(const void* base, const void* member) {
  return static_cast<std::uint32_t>(static_cast<const unsigned char*>(member) - static_cast<const unsigned char*>(base));
}


/// One output line, built in place (no formatting library: the image has no printf).
class Line {
 public:
  explicit Line(const char* tag) { text(tag); }
  void text(const char* s) {
    while (*s != '\0' && n_ < kCap - 1) buf_[n_++] = *s++;
  }
  void hex(double v) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    hex64(bits);
  }
  void hex64(std::uint64_t bits) {
    if (n_ + 17 >= kCap) return;
    buf_[n_++] = ' ';
    for (int k = 15; k >= 0; --k) buf_[n_++] = "0123456789abcdef"[(bits >> (4 * k)) & 0xFu];
  }
  void dec(std::uint32_t v) {
    char tmp[10];
    int k = 0;
    do {
      tmp[k++] = static_cast<char>('0' + v % 10u);
      v /= 10u;
    } while (v != 0u && k < 10);
    if (n_ + k + 1 >= kCap) return;
    buf_[n_++] = ' ';
    while (k > 0) buf_[n_++] = tmp[--k];
  }
  void emit(const Board& b) {
    buf_[n_++] = '\n';
    b.write(buf_, static_cast<std::size_t>(n_));
  }

 private:
  static constexpr int kCap = 2048;
  char buf_[kCap];
  int n_ = 0;
};

/// One flight application (its driver, fsw/driver.hpp) and the model's observer of it: the timing
/// bookkeeping, the 1 Hz group run apart, the output lines.
template <class Layout>
struct Model {
  const char* name;
  const Board* board = nullptr;
  fsw::FlightDriver<Layout> driver{};
  const fsw::FlightApp<Layout>& app = driver.app();
  std::uint64_t digest = fsw::kNavDigestSeed;
  std::uint32_t frames = 0, epochs = 0;
  std::uint32_t imu_ticks = 0, gnss_ticks = 0;  // 200 Hz group work since the last completed frame
  std::uint32_t ekf_ticks = 0;                  // the 1 Hz group released in this frame (run apart)
  std::uint32_t errors = 0;                     // calls that returned neither kOk nor a counted rejection
  // Before initialisation there are no frames: the worst single call (levelling, the single-point
  // fix that initialises) is kept apart.
  std::uint32_t pre_init_imu_worst = 0, pre_init_gnss_worst = 0;
  bool was_initialised = false;
  std::uint32_t t0 = 0;

  explicit Model(const char* n) : name(n) {}

  std::uint32_t elapsed(const Board& b, std::uint32_t since) const { return (since - b.ticks()) & b.tick_mask; }

  /// One event through the driver, this model observing it.
  fsw::Status step(const fsw::InputEvent& ev) { return driver.step(ev, *this); }
  // The observer (fsw/driver.hpp): the clock around the 200 Hz group's calls.
  void before(const fsw::InputEvent&) {
    was_initialised = app.initialised();
    t0 = board->ticks != nullptr ? board->ticks() : 0u;
  }
  void after(const fsw::InputEvent& ev, fsw::Status st, const fsw::FrameOutput& out) {
    const Board& b = *board;
    const bool timed = b.ticks != nullptr;
    const std::uint32_t dt = timed ? elapsed(b, t0) : 0u;
    if (ev.kind == fsw::InputEvent::Kind::kGnssRaw) {
      if (!timed) return;
      if (was_initialised)
        gnss_ticks += dt;
      else if (dt > pre_init_gnss_worst)
        pre_init_gnss_worst = dt;
      return;
    }
    if (ev.kind != fsw::InputEvent::Kind::kImu) return;
    if (timed) {
      if (was_initialised)
        imu_ticks += dt;
      else if (dt > pre_init_imu_worst)
        pre_init_imu_worst = dt;
    }
    if (st != fsw::Status::kOk && st != fsw::Status::kBadInput) ++errors;
    if (out.ekf_released) {
      // The 1 Hz group, run here as a lower-priority task would between two 200 Hz frames (its
      // correction lands ekf_latency_frames later either way), counted apart.
      const std::uint32_t t1 = timed ? b.ticks() : 0u;
      if (driver.app().run_ekf_group() != fsw::Status::kOk) ++errors;
      if (timed) ekf_ticks = elapsed(b, t1);
    }
    if (out.nav_valid) frame(b, out);
  }
  void frame(const Board& b, const fsw::FrameOutput& out) {
    const fsw::NavState& n = out.nav;
    fsw::nav_digest_add(digest, n);
    Line f("F");
    f.text(name);
    f.hex(n.t_s);
    for (int k = 0; k < 3; ++k) f.hex(n.llh[k]);
    for (int k = 0; k < 3; ++k) f.hex(n.vel_enu_mps[k]);
    f.hex(n.q_b_n.w());
    f.hex(n.q_b_n.x());
    f.hex(n.q_b_n.y());
    f.hex(n.q_b_n.z());
    f.emit(b);
    if (out.ekf_ran) {
      const auto& ekf = app.executive().ekf_output();
      Line e("E");
      e.text(name);
      e.hex(n.t_s);
      e.hex(ekf.clock_bias_m);
      e.hex(ekf.clock_drift_mps);
      e.hex(out.report.nis_sum);
      e.dec(static_cast<std::uint32_t>(out.report.pr_used));
      e.dec(static_cast<std::uint32_t>(out.report.prr_used));
      for (int k = 0; k < ekf.sigma.rows(); ++k) e.hex(ekf.sigma(k));
      e.emit(b);
      ++epochs;
    }
    if (b.ticks != nullptr) {
      Line t("T");
      t.text(name);
      t.dec(frames);
      t.dec(imu_ticks);
      t.dec(gnss_ticks);
      t.dec(out.ekf_released ? 1u : 0u);
      t.dec(ekf_ticks);
      t.emit(b);
    }
    imu_ticks = 0;
    gnss_ticks = 0;
    ekf_ticks = 0;
    ++frames;
  }
  void finish(const Board& b) {
    Line d("D");
    d.text(name);
    d.hex64(digest);
    d.dec(frames);
    d.dec(epochs);
    d.emit(b);
    const fsw::FlightAppHealth& h = app.health();
    const fsw::ExecutiveHealth& x = app.executive().health();
    Line s("S");
    s.text(name);
    s.dec(h.initialised ? 1u : 0u);
    s.hex(h.init_t_s);
    s.dec(h.imu_received);
    s.dec(h.gnss_received);
    s.dec(h.almanac_received);
    s.dec(h.almanac_rejected + h.gnss_rejected + h.imu_rejected);
    s.dec(x.ekf_runs);
    s.dec(x.ekf_updates);
    s.dec(x.pr_used);
    s.dec(x.prr_used);
    s.dec(x.fsw_errors);
    s.dec(errors);
    s.emit(b);
    if (b.ticks != nullptr) {
      Line i("I");
      i.text(name);
      i.dec(pre_init_imu_worst);
      i.dec(pre_init_gnss_worst);
      i.emit(b);
    }
  }
};

// Statically allocated, as on the target: both paper models of HIL.
Model<fsw::Layout24Full> g_m24("24");
Model<fsw::Layout15Full> g_m15("15");
fsw::FlightAppConfig g_cfg;
std::uint8_t g_cfg_wire[2048];  ///< the recorded configuration's values (fsw/flight_app_config_wire.hpp)

template <class T>
ReplayResult read_payload(const Board& b, std::uint32_t size, T& obj) {
  if (size != sizeof(T)) return ReplayResult::kBadEvent;
  return b.read(&obj, sizeof(T)) == sizeof(T) ? ReplayResult::kOk : ReplayResult::kTruncated;
}

/// The recorded input as an event source (fsw/driver.hpp): one event read from the board per
/// next(), straight into the event both models are fed; nullptr at the end of the input
/// (status kOk) or at a damaged event (status says why).
class RecordedInput {
 public:
  const fsw::InputEvent* next() {
    std::uint32_t head[2];
    const std::size_t got_head = board->read(head, sizeof head);
    if (got_head == 0) return nullptr;  // the end of the input
    if (got_head != sizeof head) return fail(ReplayResult::kTruncated);
    ReplayResult r = ReplayResult::kBadEvent;
    switch (head[0]) {
      case kTagAlmanac:
        ev_.kind = fsw::InputEvent::Kind::kAlmanac;
        r = read_payload(*board, head[1], ev_.almanac);
        break;
      case kTagGnss:
        ev_.kind = fsw::InputEvent::Kind::kGnssRaw;
        r = read_payload(*board, head[1], ev_.gnss);
        ev_.t_s = ev_.gnss.t_s;
        break;
      case kTagImu:
        ev_.kind = fsw::InputEvent::Kind::kImu;
        r = read_payload(*board, head[1], ev_.imu);
        ev_.t_s = ev_.imu.t_s;
        break;
      default: break;
    }
    return r == ReplayResult::kOk ? &ev_ : fail(r);
  }
  const Board* board = nullptr;
  ReplayResult status = ReplayResult::kOk;

 private:
  const fsw::InputEvent* fail(ReplayResult r) {
    status = r;
    return nullptr;
  }
  fsw::InputEvent ev_{};
};
RecordedInput g_input;

/// Both models of HIL fed each event: the target of the one driver loop.
struct BothModels {
  template <class Observer>
  fsw::Status step(const fsw::InputEvent& ev, Observer&) {
    const fsw::Status st = g_m24.step(ev);
    (void)g_m15.step(ev);
    return st;
  }
};

bool read_all(const Board& b, void* dst, std::size_t n) { return b.read(dst, n) == n; }

}  // namespace

void layout_fingerprint(std::uint32_t (&out)[kFingerprintWords]) {
  static const fsw::GnssRawEpoch e{};
  static const fsw::ImuSample s{};
  static const fsw::GpsAlmanac a{};
  int k = 0;
  out[k++] = static_cast<std::uint32_t>(fsw::flight_config_wire_bytes());  // the field list (not a layout)
  out[k++] = sizeof(fsw::GnssRawEpoch);
  out[k++] = offset_of(&e, &e.meas[1]);
  out[k++] = offset_of(&e, &e.meas[0].cn0_dbhz);
  out[k++] = sizeof(fsw::ImuSample);
  out[k++] = offset_of(&s, &s.dv_mps);
  out[k++] = sizeof(fsw::GpsAlmanac);
  out[k++] = offset_of(&a, &a.week_mod_1024);
  out[k++] = sizeof(fsw::Vec3) | static_cast<std::uint32_t>(alignof(fsw::GnssRawEpoch)) << 16;
}

ReplayResult run_replay(const Board& b) {
  char magic[4];
  std::uint32_t version = 0, n_fp = 0;
  if (!read_all(b, magic, 4) || std::memcmp(magic, "SDTR", 4) != 0 || !read_all(b, &version, 4) ||
      version != kFormatVersion || !read_all(b, &n_fp, 4) || n_fp != kFingerprintWords)
    return ReplayResult::kBadHeader;
  std::uint32_t want[kFingerprintWords], got[kFingerprintWords];
  layout_fingerprint(want);
  if (!read_all(b, got, sizeof got) || std::memcmp(want, got, sizeof got) != 0) return ReplayResult::kBadHeader;
  std::uint32_t cfg_bytes = 0;
  if (!read_all(b, &cfg_bytes, 4) || cfg_bytes > sizeof g_cfg_wire || !read_all(b, g_cfg_wire, cfg_bytes))
    return ReplayResult::kBadHeader;
  if (fsw::decode_flight_config(g_cfg_wire, cfg_bytes, g_cfg) != fsw::Status::kOk) return ReplayResult::kBadConfig;
  g_cfg.exec.ekf_group_inline = false;  // the two rate groups are run (and counted) apart: Model::after
  if (g_m24.driver.init(g_cfg) != fsw::Status::kOk || g_m15.driver.init(g_cfg) != fsw::Status::kOk)
    return ReplayResult::kBadConfig;
  g_m24.board = g_m15.board = g_input.board = &b;
  g_input.status = ReplayResult::kOk;
  BothModels both;
  fsw::drive(g_input, both);
  if (g_input.status != ReplayResult::kOk) return g_input.status;
  g_m24.finish(b);
  g_m15.finish(b);
  return ReplayResult::kOk;
}

namespace {

/// Uniform in [0, 1) from a 64-bit LCG (integer arithmetic: identical on both builds).
double u01(std::uint64_t& state) {
  state = state * 6364136223846793005ull + 1442695040888963407ull;
  return static_cast<double>(state >> 11) * (1.0 / 9007199254740992.0);
}

void probe_line(const Board& b, const char* name, double v) {
  Line l("L");
  l.text(name);
  l.hex(v);
  l.emit(b);
}

}  // namespace

void run_libm_probe(const Board& b) {
  std::uint64_t st = 88172645463325252ull;
  for (int i = 0; i < kLibmProbeArgs; ++i) {
    // Ranges as the flight code uses them: angles, ECEF coordinates [m], sines, exponents.
    const double angle = (2.0 * u01(st) - 1.0) * 20.0;
    const double y = (2.0 * u01(st) - 1.0) * 3e7, x = (2.0 * u01(st) - 1.0) * 3e7;
    const double s = 2.0 * u01(st) - 1.0;
    const double e = -5.0 * u01(st);
    const double p = 2e7 * u01(st) + 1.0;
    probe_line(b, "sin", std::sin(angle));
    probe_line(b, "cos", std::cos(angle));
    probe_line(b, "tan", std::tan(1.5 * s));
    probe_line(b, "asin", std::asin(s));
    probe_line(b, "atan2", std::atan2(y, x));
    probe_line(b, "exp", std::exp(e));
    probe_line(b, "hypot", std::hypot(y, x));
    probe_line(b, "pow", std::pow(p, 1.5));
  }
}

}  // namespace sdins_target
