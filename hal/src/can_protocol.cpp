// The sdins CAN FD protocol: frame encoders and decoders (see hal/can_protocol.hpp and
// hal/can/sdins.dbc). Flight-side code: no allocation, no exceptions, no I/O.
#include "hal/can_protocol.hpp"

#include <array>
#include <cmath>
#include <cstring>

namespace hal {

bool can_frame_equal(const CanFrame& a, const CanFrame& b) {
  return a.id == b.id && a.extended == b.extended && a.fd == b.fd && a.brs == b.brs && a.esi == b.esi &&
         a.len == b.len && std::memcmp(a.data.data(), b.data.data(), a.len) == 0;
}

namespace can {
namespace {

// ---- little-endian field access ----
void put_u(CanFrame& f, int byte, int nbytes, std::uint64_t v) {
  for (int i = 0; i < nbytes; ++i) f.data[static_cast<std::size_t>(byte + i)] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint64_t get_u(const CanFrame& f, int byte, int nbytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < nbytes; ++i) v |= static_cast<std::uint64_t>(f.data[static_cast<std::size_t>(byte + i)]) << (8 * i);
  return v;
}
std::int64_t get_s(const CanFrame& f, int byte, int nbytes) {
  const std::uint64_t u = get_u(f, byte, nbytes);
  if (nbytes >= 8) return static_cast<std::int64_t>(u);
  const int bits = 8 * nbytes;
  const std::uint64_t sign = std::uint64_t{1} << (bits - 1);
  return static_cast<std::int64_t>((u ^ sign) - sign);  // sign extension
}
void put_s(CanFrame& f, int byte, int nbytes, std::int64_t v) { put_u(f, byte, nbytes, static_cast<std::uint64_t>(v)); }

void start_frame(CanFrame& f, std::uint32_t id, int len) {
  f = CanFrame{};
  f.id = id;
  f.extended = false;
  f.fd = true;
  f.brs = true;
  f.len = static_cast<std::uint8_t>(len);
}

/// round(x) as an integer when it lies in [lo, hi]; false for non-finite or out-of-range x.
bool to_int(double x, double lo, double hi, std::int64_t& out) {
  if (!std::isfinite(x)) return false;
  const double r = std::nearbyint(x);
  if (r < lo || r > hi) return false;
  out = static_cast<std::int64_t>(r);
  return true;
}

constexpr double kI32Min = -2147483648.0, kI32Max = 2147483647.0;
constexpr double kU32Max = 4294967295.0;
constexpr double kI40Min = -549755813888.0, kI40Max = 549755813887.0;
constexpr double kU40Max = 1099511627775.0;
constexpr double kI64Lim = 9.2e18;  // inside the int64 range, far beyond any time tag

// IMU_SAMPLE layout (byte offsets)
constexpr int kImuCounter = 0, kImuTime = 4, kImuDt = 12, kImuDtheta = 16, kImuDv = 28, kImuStatus = 40;
// GPS_EPOCH
constexpr int kEpSeq = 0, kEpWeek = 2, kEpTow = 4, kEpTime = 12, kEpNMeas = 20, kEpStatus = 21;
// GPS_MEAS
constexpr int kMsSeq = 0, kMsIndex = 2, kMsPrn = 3, kMsPr = 4, kMsPrr = 9, kMsCn0 = 13;
// GPS_ALMANAC
constexpr int kAlPrn = 0, kAlHealth = 1, kAlWeek = 2, kAlToa = 4, kAlEcc = 8, kAlDeltaI = 12, kAlOmegaDot = 17,
              kAlSqrtA = 22, kAlOmega0 = 27, kAlArgPerigee = 32, kAlM0 = 37, kAlAf0 = 42, kAlAf1 = 47;

// SIM_CONTROL
constexpr int kScCommand = 0, kScMode = 1, kScWindow = 2, kScRunId = 4, kScSeed = 8, kScSteps = 16, kScImu = 20,
              kScFrames = 24;
// FSW_ACK
constexpr int kAkRunId = 0, kAkImuFrames = 4, kAkFrames = 8, kAkImuDelivered = 12, kAkNavFrames = 16, kAkFlags = 20;

constexpr double kSecondsPerWeek = 604800.0;

/// Angle [rad] -> semicircles in [-1, 1).
double wrap_semicircles(double rad) {
  double sc = rad / kSemicircle_rad;
  sc = std::fmod(sc, 2.0);  // (-2, 2)
  if (sc >= 1.0) sc -= 2.0;
  if (sc < -1.0) sc += 2.0;
  return sc;
}

}  // namespace

const MessageInfo* message_info(const CanFrame& f) {
  if (f.extended) return nullptr;
  for (const MessageInfo& m : kMessages)
    if (m.id == f.id) return &m;
  return nullptr;
}

const char* to_string(CodecStatus s) {
  switch (s) {
    case CodecStatus::kOk: return "ok";
    case CodecStatus::kFlagged: return "flagged";
    case CodecStatus::kUnknownId: return "unknown_id";
    case CodecStatus::kBadLength: return "bad_length";
    case CodecStatus::kBadCrc: return "bad_crc";
    case CodecStatus::kBadInput: return "bad_input";
    case CodecStatus::kOutOfRange: return "out_of_range";
  }
  return "unknown";
}

namespace {

// CRC-16/CCITT-FALSE eight bytes at a time ("slicing by 8"). Table 0, entry b: the register's
// change for the top byte b shifted through the eight polynomial steps (the bitwise definition,
// evaluated here at compile time); table k: byte b followed by k zero bytes. The CRC is linear, so
// eight bytes from register c are the sum of each byte's table entry for the bytes after it, with
// c folded into the first two bytes. Every IMU sample is sealed by the simulator and checked by
// the receiver: bit by bit this was 61 % of a SIL run (docs/performance.md).
using Crc16Tables = std::array<std::array<std::uint16_t, 256>, 8>;
constexpr Crc16Tables crc16_ccitt_tables() {
  Crc16Tables t{};
  for (unsigned b = 0; b < 256; ++b) {
    std::uint16_t crc = static_cast<std::uint16_t>(b << 8);
    for (int k = 0; k < 8; ++k)
      crc = (crc & 0x8000u) ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021u) : static_cast<std::uint16_t>(crc << 1);
    t[0][b] = crc;
  }
  for (std::size_t k = 1; k < 8; ++k)
    for (unsigned b = 0; b < 256; ++b) {
      const std::uint16_t r = t[k - 1][b];
      t[k][b] = static_cast<std::uint16_t>((r << 8) ^ t[0][r >> 8]);
    }
  return t;
}
constexpr Crc16Tables kCrc16 = crc16_ccitt_tables();

}  // namespace

std::uint16_t crc16_ccitt(const std::uint8_t* data, int n, std::uint16_t crc) {
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    const std::uint8_t* d = data + i;
    crc = static_cast<std::uint16_t>(kCrc16[7][d[0] ^ (crc >> 8)] ^ kCrc16[6][d[1] ^ (crc & 0xFFu)] ^ kCrc16[5][d[2]] ^
                                     kCrc16[4][d[3]] ^ kCrc16[3][d[4]] ^ kCrc16[2][d[5]] ^ kCrc16[1][d[6]] ^
                                     kCrc16[0][d[7]]);
  }
  for (; i < n; ++i) crc = static_cast<std::uint16_t>((crc << 8) ^ kCrc16[0][((crc >> 8) ^ data[i]) & 0xFFu]);
  return crc;
}

std::uint16_t frame_crc(const CanFrame& f) {
  const std::uint8_t id_le[2] = {static_cast<std::uint8_t>(f.id & 0xFFu), static_cast<std::uint8_t>((f.id >> 8) & 0xFFu)};
  const std::uint16_t c = crc16_ccitt(id_le, 2);
  return f.len >= 2 ? crc16_ccitt(f.data.data(), f.len - 2, c) : c;
}

void seal_frame(CanFrame& f) {
  if (f.len < 2) return;
  put_u(f, f.len - 2, 2, frame_crc(f));
}

CodecStatus check_frame(const CanFrame& f, MessageKind& kind) {
  kind = MessageKind::kUnknown;
  const MessageInfo* m = message_info(f);
  if (m == nullptr) return CodecStatus::kUnknownId;
  kind = m->kind;
  if (f.len != m->len) return CodecStatus::kBadLength;
  if (get_u(f, f.len - 2, 2) != frame_crc(f)) return CodecStatus::kBadCrc;
  return CodecStatus::kOk;
}

namespace {
CodecStatus check_kind(const CanFrame& f, MessageKind want) {
  MessageKind k;
  const CodecStatus s = check_frame(f, k);
  if (k != want) return CodecStatus::kUnknownId;
  return s;
}
}  // namespace

// ---- IMU ----------------------------------------------------------------------------------------

CodecStatus ImuEncoder::encode(const fsw::ImuSample& s, CanFrame& out, std::uint16_t extra_status) {
  const std::uint32_t counter = counter_++;
  if (!std::isfinite(s.t_s) || !std::isfinite(s.dt_s) || !(s.dt_s > 0.0)) return CodecStatus::kBadInput;
  std::int64_t t_ns = 0, dt_ns = 0;
  if (!to_int(s.t_s * kTimeNsPerS, -kI64Lim, kI64Lim, t_ns) || !to_int(s.dt_s * kTimeNsPerS, 1.0, kU32Max, dt_ns))
    return CodecStatus::kOutOfRange;

  std::uint16_t status = static_cast<std::uint16_t>(extra_status & (kImuGyroFail | kImuAccelFail));
  std::int32_t q_dth[3] = {0, 0, 0}, q_dv[3] = {0, 0, 0};
  const bool finite = s.dtheta_rad.allFinite() && s.dv_mps.allFinite();
  if (!finite) {
    status |= kImuSampleInvalid;
  } else {
    auto quantize = [&status](double value, double per_unit, double& residual, std::int32_t& q, std::uint16_t sat_bit) {
      const double want = value * per_unit + residual;
      double r = std::nearbyint(want);
      if (r > kI32Max || r < kI32Min) {
        r = r > 0 ? kI32Max : kI32Min;
        status |= sat_bit;
        residual = 0.0;
      } else {
        residual = want - r;
      }
      q = static_cast<std::int32_t>(r);
    };
    for (int i = 0; i < 3; ++i) {
      quantize(s.dtheta_rad(i), kDthetaPerRad, res_dtheta_[i], q_dth[i], kImuDthetaSaturated);
      quantize(s.dv_mps(i), kDvPerMps, res_dv_[i], q_dv[i], kImuDvSaturated);
    }
  }
  start_frame(out, kIdImuSample, kLenImuSample);
  put_u(out, kImuCounter, 4, counter);
  put_s(out, kImuTime, 8, t_ns);
  put_u(out, kImuDt, 4, static_cast<std::uint64_t>(dt_ns));
  for (int i = 0; i < 3; ++i) {
    put_s(out, kImuDtheta + 4 * i, 4, q_dth[i]);
    put_s(out, kImuDv + 4 * i, 4, q_dv[i]);
  }
  put_u(out, kImuStatus, 2, status);
  seal_frame(out);
  return finite ? CodecStatus::kOk : CodecStatus::kFlagged;
}

CodecStatus decode_imu(const CanFrame& f, ImuFrame& out) {
  const CodecStatus st = check_kind(f, MessageKind::kImuSample);
  if (st != CodecStatus::kOk) return st;
  out.counter = static_cast<std::uint32_t>(get_u(f, kImuCounter, 4));
  out.time_ns = get_s(f, kImuTime, 8);
  out.dt_ns = static_cast<std::uint32_t>(get_u(f, kImuDt, 4));
  out.status = static_cast<std::uint16_t>(get_u(f, kImuStatus, 2));
  out.sample.t_s = static_cast<double>(out.time_ns) / kTimeNsPerS;
  out.sample.dt_s = static_cast<double>(out.dt_ns) / kTimeNsPerS;
  for (int i = 0; i < 3; ++i) {
    out.sample.dtheta_rad(i) = static_cast<double>(get_s(f, kImuDtheta + 4 * i, 4)) / kDthetaPerRad;
    out.sample.dv_mps(i) = static_cast<double>(get_s(f, kImuDv + 4 * i, 4)) / kDvPerMps;
  }
  return CodecStatus::kOk;
}

// ---- GPS epoch and measurements ---------------------------------------------------------------

CodecStatus encode_gps_epoch(std::uint16_t seq, int gps_week, double gps_tow_s, double t_s, int n_meas,
                             std::uint8_t status, CanFrame& out) {
  if (!std::isfinite(gps_tow_s) || !std::isfinite(t_s)) return CodecStatus::kBadInput;
  if (gps_week < 0 || gps_week > 65535 || n_meas < 0 || n_meas > fsw::kMaxGnssChannels)
    return CodecStatus::kOutOfRange;
  std::int64_t tow_ns = 0, t_ns = 0;
  if (!to_int(gps_tow_s * kTimeNsPerS, 0.0, kSecondsPerWeek * kTimeNsPerS - 1.0, tow_ns) ||
      !to_int(t_s * kTimeNsPerS, -kI64Lim, kI64Lim, t_ns))
    return CodecStatus::kOutOfRange;
  start_frame(out, kIdGpsEpoch, kLenGpsEpoch);
  put_u(out, kEpSeq, 2, seq);
  put_u(out, kEpWeek, 2, static_cast<std::uint64_t>(gps_week));
  put_u(out, kEpTow, 8, static_cast<std::uint64_t>(tow_ns));
  put_s(out, kEpTime, 8, t_ns);
  put_u(out, kEpNMeas, 1, static_cast<std::uint64_t>(n_meas));
  put_u(out, kEpStatus, 1, status);
  seal_frame(out);
  return CodecStatus::kOk;
}

CodecStatus encode_gps_meas(std::uint16_t seq, int index, const fsw::GnssRawMeasurement& m, CanFrame& out) {
  if (index < 0 || index > 255) return CodecStatus::kOutOfRange;
  if (!std::isfinite(m.pseudorange_m) || !std::isfinite(m.pseudorange_rate_mps) || !std::isfinite(m.cn0_dbhz))
    return CodecStatus::kBadInput;
  if (m.prn == 0) return CodecStatus::kBadInput;
  std::int64_t pr = 0, prr = 0, cn0 = 0;
  if (!to_int(m.pseudorange_m * kPseudorangePerM, kI40Min, kI40Max, pr) ||
      !to_int(m.pseudorange_rate_mps * kRangeRatePerMps, kI32Min, kI32Max, prr) ||
      !to_int(m.cn0_dbhz * kCn0PerDbHz, 0.0, 65535.0, cn0))
    return CodecStatus::kOutOfRange;
  start_frame(out, kIdGpsMeas, kLenGpsMeas);
  put_u(out, kMsSeq, 2, seq);
  put_u(out, kMsIndex, 1, static_cast<std::uint64_t>(index));
  put_u(out, kMsPrn, 1, m.prn);
  put_s(out, kMsPr, 5, pr);
  put_s(out, kMsPrr, 4, prr);
  put_u(out, kMsCn0, 2, static_cast<std::uint64_t>(cn0));
  seal_frame(out);
  return CodecStatus::kOk;
}

CodecStatus decode_gps_epoch(const CanFrame& f, GpsEpochFrame& out) {
  const CodecStatus st = check_kind(f, MessageKind::kGpsEpoch);
  if (st != CodecStatus::kOk) return st;
  out.seq = static_cast<std::uint16_t>(get_u(f, kEpSeq, 2));
  out.gps_week = static_cast<int>(get_u(f, kEpWeek, 2));
  out.tow_ns = get_u(f, kEpTow, 8);
  out.gps_tow_s = static_cast<double>(out.tow_ns) / kTimeNsPerS;
  out.t_ns = get_s(f, kEpTime, 8);
  out.t_s = static_cast<double>(out.t_ns) / kTimeNsPerS;
  out.n_meas = static_cast<std::uint8_t>(get_u(f, kEpNMeas, 1));
  out.status = static_cast<std::uint8_t>(get_u(f, kEpStatus, 1));
  return CodecStatus::kOk;
}

CodecStatus decode_gps_meas(const CanFrame& f, GpsMeasFrame& out) {
  const CodecStatus st = check_kind(f, MessageKind::kGpsMeas);
  if (st != CodecStatus::kOk) return st;
  out.seq = static_cast<std::uint16_t>(get_u(f, kMsSeq, 2));
  out.index = static_cast<std::uint8_t>(get_u(f, kMsIndex, 1));
  out.meas.prn = static_cast<std::uint8_t>(get_u(f, kMsPrn, 1));
  out.meas.pseudorange_m = static_cast<double>(get_s(f, kMsPr, 5)) / kPseudorangePerM;
  out.meas.pseudorange_rate_mps = static_cast<double>(get_s(f, kMsPrr, 4)) / kRangeRatePerMps;
  out.meas.cn0_dbhz = static_cast<double>(get_u(f, kMsCn0, 2)) / kCn0PerDbHz;
  return CodecStatus::kOk;
}

CodecStatus GpsEncoder::encode(const fsw::GnssRawEpoch& epoch, CanFrame* out, int& n_out, int& n_skipped) {
  n_out = 0;
  n_skipped = 0;
  if (epoch.n_meas < 0 || epoch.n_meas > fsw::kMaxGnssChannels) return CodecStatus::kOutOfRange;
  const std::uint16_t seq = seq_;
  int n = 0;
  for (int i = 0; i < epoch.n_meas; ++i) {
    if (encode_gps_meas(seq, n, epoch.meas[static_cast<std::size_t>(i)], out[1 + n]) == CodecStatus::kOk)
      ++n;
    else
      ++n_skipped;
  }
  const CodecStatus st = encode_gps_epoch(seq, epoch.gps_week, epoch.gps_tow_s, epoch.t_s, n, kGpsTimeValid, out[0]);
  if (st != CodecStatus::kOk) {
    n_skipped = 0;
    return st;
  }
  ++seq_;
  n_out = 1 + n;
  return CodecStatus::kOk;
}

// ---- almanac ------------------------------------------------------------------------------------

CodecStatus encode_gps_almanac(const fsw::GpsAlmanac& a, CanFrame& out) {
  const double vals[] = {a.eccentricity, a.toa_s, a.inclination_rad, a.omega_dot_radps, a.sqrt_a_sqrtm, a.omega0_rad,
                         a.arg_perigee_rad, a.mean_anomaly_rad, a.af0_s, a.af1_sps};
  for (double v : vals)
    if (!std::isfinite(v)) return CodecStatus::kBadInput;
  if (a.prn < 0 || a.prn > 255 || a.health < 0 || a.health > 255 || a.week_mod_1024 < 0 || a.week_mod_1024 > 65535)
    return CodecStatus::kOutOfRange;
  std::int64_t toa = 0, ecc = 0, di = 0, odot = 0, sqa = 0, om0 = 0, w = 0, m0 = 0, af0 = 0, af1 = 0;
  const double di_sc = a.inclination_rad / kSemicircle_rad - kAlmInclinationRef_sc;
  if (!to_int(a.toa_s / kAlmToaLsb_s, 0.0, kU32Max, toa) || !to_int(a.eccentricity / kAlmEccLsb, 0.0, kU32Max, ecc) ||
      !to_int(di_sc / kAlmAngleLsb_sc, kI40Min, kI40Max, di) ||
      !to_int(a.omega_dot_radps / kSemicircle_rad / kAlmOmegaDotLsb_scps, kI40Min, kI40Max, odot) ||
      !to_int(a.sqrt_a_sqrtm / kAlmSqrtALsb, 0.0, kU40Max, sqa) ||
      !to_int(a.af0_s / kAlmAf0Lsb_s, kI40Min, kI40Max, af0) || !to_int(a.af1_sps / kAlmAf1Lsb_sps, kI40Min, kI40Max, af1))
    return CodecStatus::kOutOfRange;
  // Periodic angles: [-1, 1) semicircles; a value that rounds up to +1 semicircle wraps to -1.
  auto angle = [](double rad) {
    std::int64_t q = static_cast<std::int64_t>(std::nearbyint(wrap_semicircles(rad) / kAlmAngleLsb_sc));
    if (q > static_cast<std::int64_t>(kI40Max)) q -= std::int64_t{1} << 40;
    return q;
  };
  om0 = angle(a.omega0_rad);
  w = angle(a.arg_perigee_rad);
  m0 = angle(a.mean_anomaly_rad);

  start_frame(out, kIdGpsAlmanac, kLenGpsAlmanac);
  put_u(out, kAlPrn, 1, static_cast<std::uint64_t>(a.prn));
  put_u(out, kAlHealth, 1, static_cast<std::uint64_t>(a.health));
  put_u(out, kAlWeek, 2, static_cast<std::uint64_t>(a.week_mod_1024));
  put_u(out, kAlToa, 4, static_cast<std::uint64_t>(toa));
  put_u(out, kAlEcc, 4, static_cast<std::uint64_t>(ecc));
  put_s(out, kAlDeltaI, 5, di);
  put_s(out, kAlOmegaDot, 5, odot);
  put_u(out, kAlSqrtA, 5, static_cast<std::uint64_t>(sqa));
  put_s(out, kAlOmega0, 5, om0);
  put_s(out, kAlArgPerigee, 5, w);
  put_s(out, kAlM0, 5, m0);
  put_s(out, kAlAf0, 5, af0);
  put_s(out, kAlAf1, 5, af1);
  seal_frame(out);
  return CodecStatus::kOk;
}

CodecStatus decode_gps_almanac(const CanFrame& f, fsw::GpsAlmanac& a) {
  const CodecStatus st = check_kind(f, MessageKind::kGpsAlmanac);
  if (st != CodecStatus::kOk) return st;
  a = fsw::GpsAlmanac{};
  a.prn = static_cast<int>(get_u(f, kAlPrn, 1));
  a.health = static_cast<int>(get_u(f, kAlHealth, 1));
  a.week_mod_1024 = static_cast<int>(get_u(f, kAlWeek, 2));
  a.toa_s = static_cast<double>(get_u(f, kAlToa, 4)) * kAlmToaLsb_s;
  a.eccentricity = static_cast<double>(get_u(f, kAlEcc, 4)) * kAlmEccLsb;
  a.inclination_rad = (kAlmInclinationRef_sc + static_cast<double>(get_s(f, kAlDeltaI, 5)) * kAlmAngleLsb_sc) * kSemicircle_rad;
  a.omega_dot_radps = static_cast<double>(get_s(f, kAlOmegaDot, 5)) * kAlmOmegaDotLsb_scps * kSemicircle_rad;
  a.sqrt_a_sqrtm = static_cast<double>(get_u(f, kAlSqrtA, 5)) * kAlmSqrtALsb;
  a.omega0_rad = static_cast<double>(get_s(f, kAlOmega0, 5)) * kAlmAngleLsb_sc * kSemicircle_rad;
  a.arg_perigee_rad = static_cast<double>(get_s(f, kAlArgPerigee, 5)) * kAlmAngleLsb_sc * kSemicircle_rad;
  a.mean_anomaly_rad = static_cast<double>(get_s(f, kAlM0, 5)) * kAlmAngleLsb_sc * kSemicircle_rad;
  a.af0_s = static_cast<double>(get_s(f, kAlAf0, 5)) * kAlmAf0Lsb_s;
  a.af1_sps = static_cast<double>(get_s(f, kAlAf1, 5)) * kAlmAf1Lsb_sps;
  return CodecStatus::kOk;
}

// ---- one simulator step ---------------------------------------------------------------------------

CanStepEncoder::Result CanStepEncoder::encode(const fsw::ImuSample* imu, int n_imu, const fsw::GnssRawEpoch* epoch,
                                              const fsw::GpsAlmanac* alm, int n_alm, CanFrame* out) {
  Result r;
  for (int i = 0; i < n_imu; ++i) {
    const CodecStatus st = imu_.encode(imu[i], out[r.n_frames]);
    if (st == CodecStatus::kOk || st == CodecStatus::kFlagged) {
      ++r.n_frames;
      if (st == CodecStatus::kFlagged) ++r.imu_flagged;
    } else {
      ++r.imu_rejected;
    }
  }
  if (epoch != nullptr) {
    int n = 0, skipped = 0;
    if (gps_.encode(*epoch, out + r.n_frames, n, skipped) == CodecStatus::kOk)
      r.n_frames += n;
    else
      r.gps_rejected = 1;
    r.gps_skipped = skipped;
  }
  for (int i = 0; i < n_alm; ++i) {
    if (encode_gps_almanac(alm[i], out[r.n_frames]) == CodecStatus::kOk)
      ++r.n_frames;
    else
      ++r.almanac_rejected;
  }
  return r;
}

// ---- bus timing -----------------------------------------------------------------------------------

double can_fd_frame_time_s(int payload_len, double nominal_bps, double data_bps) {
  const int n = payload_len;
  // Nominal rate: SOF, 11-bit ID, RRS, IDE, FDF, res, BRS (17 bits, up to 4 stuff bits), then
  // CRC delimiter, ACK slot, ACK delimiter, EOF (7) and intermission (3).
  const double nominal_bits = 17.0 + 4.0 + 13.0;
  // Data rate: ESI, DLC (4), payload; dynamic stuffing up to one bit in four; stuff count (4),
  // CRC-17 (<= 16 bytes) or CRC-21 with a fixed stuff bit every 4 bits of count + CRC.
  const int dyn = 5 + 8 * n;
  const int crc = n <= 16 ? 17 : 21;
  const double data_bits = dyn + std::ceil(dyn / 4.0) + 4 + crc + std::ceil((4 + crc) / 4.0);
  return nominal_bits / nominal_bps + data_bits / data_bps;
}

// ---- lockstep flow control ----------------------------------------------------------------------

namespace {
bool sim_control_valid(std::uint64_t command, std::uint64_t mode) {
  return (command == static_cast<std::uint64_t>(SimCommand::kStart) ||
          command == static_cast<std::uint64_t>(SimCommand::kEnd)) &&
         (mode == static_cast<std::uint64_t>(SimMode::kLockstep) || mode == static_cast<std::uint64_t>(SimMode::kRealtime));
}
}  // namespace

CodecStatus encode_sim_control(const SimControlFrame& c, CanFrame& out) {
  if (!sim_control_valid(static_cast<std::uint64_t>(c.command), static_cast<std::uint64_t>(c.mode)))
    return CodecStatus::kBadInput;
  start_frame(out, kIdSimControl, kLenSimControl);
  put_u(out, kScCommand, 1, static_cast<std::uint64_t>(c.command));
  put_u(out, kScMode, 1, static_cast<std::uint64_t>(c.mode));
  put_u(out, kScWindow, 2, c.window_imu);
  put_u(out, kScRunId, 4, c.run_id);
  put_u(out, kScSeed, 8, c.seed);
  put_u(out, kScSteps, 4, c.steps);
  put_u(out, kScImu, 4, c.imu_samples);
  put_u(out, kScFrames, 4, c.frames);
  seal_frame(out);
  return CodecStatus::kOk;
}

CodecStatus decode_sim_control(const CanFrame& f, SimControlFrame& out) {
  const CodecStatus st = check_kind(f, MessageKind::kSimControl);
  if (st != CodecStatus::kOk) return st;
  const std::uint64_t cmd = get_u(f, kScCommand, 1), mode = get_u(f, kScMode, 1);
  out.command = static_cast<SimCommand>(cmd);
  out.mode = static_cast<SimMode>(mode);
  out.window_imu = static_cast<std::uint16_t>(get_u(f, kScWindow, 2));
  out.run_id = static_cast<std::uint32_t>(get_u(f, kScRunId, 4));
  out.seed = get_u(f, kScSeed, 8);
  out.steps = static_cast<std::uint32_t>(get_u(f, kScSteps, 4));
  out.imu_samples = static_cast<std::uint32_t>(get_u(f, kScImu, 4));
  out.frames = static_cast<std::uint32_t>(get_u(f, kScFrames, 4));
  return sim_control_valid(cmd, mode) ? CodecStatus::kOk : CodecStatus::kBadInput;
}

void encode_fsw_ack(const FswAckFrame& a, CanFrame& out) {
  start_frame(out, kIdFswAck, kLenFswAck);
  put_u(out, kAkRunId, 4, a.run_id);
  put_u(out, kAkImuFrames, 4, a.imu_frames);
  put_u(out, kAkFrames, 4, a.frames);
  put_u(out, kAkImuDelivered, 4, a.imu_delivered);
  put_u(out, kAkNavFrames, 4, a.nav_frames);
  put_u(out, kAkFlags, 1, a.flags);
  seal_frame(out);
}

CodecStatus decode_fsw_ack(const CanFrame& f, FswAckFrame& out) {
  const CodecStatus st = check_kind(f, MessageKind::kFswAck);
  if (st != CodecStatus::kOk) return st;
  out.run_id = static_cast<std::uint32_t>(get_u(f, kAkRunId, 4));
  out.imu_frames = static_cast<std::uint32_t>(get_u(f, kAkImuFrames, 4));
  out.frames = static_cast<std::uint32_t>(get_u(f, kAkFrames, 4));
  out.imu_delivered = static_cast<std::uint32_t>(get_u(f, kAkImuDelivered, 4));
  out.nav_frames = static_cast<std::uint32_t>(get_u(f, kAkNavFrames, 4));
  out.flags = static_cast<std::uint8_t>(get_u(f, kAkFlags, 1));
  return CodecStatus::kOk;
}

double can_classic_frame_time_s(int payload_len, double bps) {
  // SOF..CRC (34 + 8n bits, stuffed), CRC delimiter, ACK, ACK delimiter, EOF, intermission (13).
  const int stuffed = 34 + 8 * payload_len;
  return (stuffed + std::floor((stuffed - 1) / 4.0) + 13.0) / bps;
}

}  // namespace can
}  // namespace hal
