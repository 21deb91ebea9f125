// The sdins CAN FD protocol for the IMU and the GPS receiver: identifiers, signal scaling, the
// frame encoders and decoders. hal/can/sdins.dbc is the same protocol in DBC form (the two are
// kept identical by the canmatrix test in tests/e2e/can_canmatrix.py); docs/can.md explains
// the choices.
//
// All frames are CAN FD with bit rate switch, 11-bit identifiers, little-endian (Intel) signals,
// and end in a CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final XOR) over
// the identifier (2 bytes, little-endian) followed by the payload bytes before the CRC. The CRC
// is an end-to-end check: it also protects frames on the UDP transport and in log files, which
// have no CAN link-layer CRC.
//
//   ID     name         len  rate              content
//   0x010  IMU_SAMPLE    48  IMU rate (1 kHz)  counter, time tag, dt, delta-theta, delta-v, status
//   0x020  GPS_EPOCH     24  GPS rate (1 Hz)   epoch sequence, week, tow (receiver clock), IMU-time
//                                              receive time, number of measurement frames, status
//   0x021  GPS_MEAS      20  per satellite     epoch sequence, index, PRN, pseudorange, rate, C/N0
//   0x030  GPS_ALMANAC   64  per PRN           all fsw::GpsAlmanac elements, IS-GPS-200 units
//   0x040  SIM_CONTROL   32  run start / end   bus simulator -> fsw: run id, mode, window, seed, totals
//   0x041  FSW_ACK       24  every minor frame fsw -> bus simulator: IMU frames / frames consumed
//
// SIM_CONTROL and FSW_ACK are the lockstep flow control of HIL runs (docs/running.md, "Lockstep protocol");
// they carry no sensor data, so the receive assembler only counts them (control_frames) and
// hal::CanFswInput takes them out before it. Their IDs are the lowest priority on the bus: a
// control frame never delays a sensor frame in arbitration.
//
// Decimal scale factors are applied as integer = round(value * N), value = integer / N (N an
// exactly representable power of ten), binary ones as exact multiplications by powers of two, so
// decode -> encode -> decode reproduces the decoded values bit for bit. Decoding is a pure
// function of the frame bytes: every consumer (in-process SIL, a process behind a bus, a replay)
// gets bit-identical fsw inputs.
//
// Flight-side code: no allocation, no exceptions, no I/O (compiled with -fno-exceptions).
#pragma once

#include <cstdint>

#include "fsw/gps_orbit.hpp"
#include "fsw/strapdown.hpp"
#include "hal/can_frame.hpp"

namespace hal::can {

// ---- identifiers and lengths -----------------------------------------------------------------
inline constexpr std::uint32_t kIdImuSample = 0x010;
inline constexpr std::uint32_t kIdGpsEpoch = 0x020;
inline constexpr std::uint32_t kIdGpsMeas = 0x021;
inline constexpr std::uint32_t kIdGpsAlmanac = 0x030;
inline constexpr std::uint32_t kIdSimControl = 0x040;
inline constexpr std::uint32_t kIdFswAck = 0x041;

inline constexpr int kLenImuSample = 48;
inline constexpr int kLenGpsEpoch = 24;
inline constexpr int kLenGpsMeas = 20;
inline constexpr int kLenGpsAlmanac = 64;
inline constexpr int kLenSimControl = 32;
inline constexpr int kLenFswAck = 24;

enum class MessageKind : std::uint8_t { kUnknown, kImuSample, kGpsEpoch, kGpsMeas, kGpsAlmanac, kSimControl, kFswAck };

struct MessageInfo {
  std::uint32_t id;
  MessageKind kind;
  const char* name;
  int len;
};
inline constexpr MessageInfo kMessages[] = {
    {kIdImuSample, MessageKind::kImuSample, "IMU_SAMPLE", kLenImuSample},
    {kIdGpsEpoch, MessageKind::kGpsEpoch, "GPS_EPOCH", kLenGpsEpoch},
    {kIdGpsMeas, MessageKind::kGpsMeas, "GPS_MEAS", kLenGpsMeas},
    {kIdGpsAlmanac, MessageKind::kGpsAlmanac, "GPS_ALMANAC", kLenGpsAlmanac},
    {kIdSimControl, MessageKind::kSimControl, "SIM_CONTROL", kLenSimControl},
    {kIdFswAck, MessageKind::kFswAck, "FSW_ACK", kLenFswAck},
};
/// The message of a frame's identifier (extended identifiers are never ours), nullptr if unknown.
const MessageInfo* message_info(const CanFrame& f);

// ---- scaling (physical = raw / k*PerUnit, or raw * LSB for binary scaling) -------------------
inline constexpr double kTimeNsPerS = 1e9;          ///< time tags, dt: 1 ns, int64 / uint32
inline constexpr double kDthetaPerRad = 1e11;       ///< delta-theta: 1e-11 rad, int32 (+-0.0215 rad)
inline constexpr double kDvPerMps = 1e9;            ///< delta-v: 1e-9 m/s, int32 (+-2.147 m/s)
inline constexpr double kPseudorangePerM = 1e4;     ///< pseudorange: 0.1 mm, int40 (+-5.5e7 m)
inline constexpr double kRangeRatePerMps = 1e4;     ///< pseudorange rate: 0.1 mm/s, int32 (+-2.1e5 m/s)
inline constexpr double kCn0PerDbHz = 100.0;        ///< C/N0: 0.01 dB-Hz, uint16 (0..655 dB-Hz)
inline constexpr double kPseudorangeMax_m = 549755813887.0 / kPseudorangePerM;  ///< (2^39 - 1) LSB
// Almanac: IS-GPS-200 units (semicircles, powers of two) with fields 2^12 ... 2^20 times finer
// than the almanac's (Table 20-VI), so every IS-GPS-200 almanac value is carried exactly and
// arbitrary elements (e.g. a simulator's) so finely that the orbit and clock computed from the
// decoded elements stay within a millimetre of the original ones for a day.
inline constexpr double kAlmToaLsb_s = 0x1p-8;              ///< uint32
inline constexpr double kAlmEccLsb = 0x1p-33;               ///< uint32, [0, 0.5)
inline constexpr double kAlmAngleLsb_sc = 0x1p-39;          ///< int40, semicircles: i0 - 0.3, Omega0, omega, M0
inline constexpr double kAlmInclinationRef_sc = 0.3;        ///< i0 = 0.3 semicircles + delta-i (IS-GPS-200)
inline constexpr double kAlmOmegaDotLsb_scps = 0x1p-56;     ///< int40, semicircles/s
inline constexpr double kAlmSqrtALsb = 0x1p-27;             ///< uint40, m^0.5, [0, 8192)
inline constexpr double kAlmAf0Lsb_s = 0x1p-39;             ///< int40, [-1, 1) s
inline constexpr double kAlmAf1Lsb_sps = 0x1p-55;           ///< int40, [-1.5e-5, 1.5e-5)
inline constexpr double kSemicircle_rad = fsw::kPi;  ///< IS-GPS-200 pi

// ---- status bits -----------------------------------------------------------------------------
/// IMU_SAMPLE ImuStatus (16 bits; the others are reserved and sent as 0).
enum ImuStatusBit : std::uint16_t {
  kImuGyroFail = 1u << 0,          ///< the IMU reports a gyro failure: sample unusable
  kImuAccelFail = 1u << 1,         ///< the IMU reports an accelerometer failure: sample unusable
  kImuDthetaSaturated = 1u << 2,   ///< a delta-theta component was clamped to the field's range
  kImuDvSaturated = 1u << 3,       ///< a delta-v component was clamped to the field's range
  kImuSampleInvalid = 1u << 4,     ///< the increments were not finite: zeros sent, sample unusable
};
inline constexpr std::uint16_t kImuUnusableMask = kImuGyroFail | kImuAccelFail | kImuSampleInvalid;
/// GPS_EPOCH GpsStatus (8 bits).
enum GpsStatusBit : std::uint8_t {
  kGpsTimeValid = 1u << 0,  ///< week/tow are valid (set by every encoder here)
};

// ---- codec -----------------------------------------------------------------------------------
enum class CodecStatus : std::uint8_t {
  kOk = 0,
  kFlagged,      ///< encoder: frame made, but the sample was flagged unusable (non-finite increments)
  kUnknownId,    ///< decoder: not one of our identifiers (or an extended / remote frame)
  kBadLength,    ///< decoder: payload length differs from the message's
  kBadCrc,       ///< decoder: end-to-end CRC mismatch (corrupted payload)
  kBadInput,     ///< encoder: non-finite or invalid input (no frame made)
  kOutOfRange,   ///< encoder: a value does not fit its field (no frame made)
};
const char* to_string(CodecStatus s);

/// CRC-16/CCITT-FALSE of a byte range, continuing from crc.
std::uint16_t crc16_ccitt(const std::uint8_t* data, int n, std::uint16_t crc = 0xFFFF);
/// The frame CRC: over the identifier's two little-endian bytes and payload bytes [0, len - 2).
std::uint16_t frame_crc(const CanFrame& f);
/// Identifier, length and CRC of one of our frames: kOk, kUnknownId, kBadLength or kBadCrc.
CodecStatus check_frame(const CanFrame& f, MessageKind& kind);

/// One decoded IMU_SAMPLE.
struct ImuFrame {
  std::uint32_t counter = 0;
  std::uint16_t status = 0;
  std::int64_t time_ns = 0;
  std::uint32_t dt_ns = 0;
  fsw::ImuSample sample{};  ///< t_s = time_ns / 1e9, dt_s = dt_ns / 1e9, increments scaled
};
/// One decoded GPS_EPOCH (the header of a receiver epoch).
struct GpsEpochFrame {
  std::uint16_t seq = 0;
  std::uint8_t n_meas = 0;   ///< GPS_MEAS frames that follow (0..16 when plausible)
  std::uint8_t status = 0;
  int gps_week = 0;
  std::uint64_t tow_ns = 0;
  double gps_tow_s = 0.0;    ///< receiver clock, tow_ns / 1e9
  std::int64_t t_ns = 0;
  double t_s = 0.0;          ///< receive time on the IMU time scale, t_ns / 1e9
};
/// One decoded GPS_MEAS.
struct GpsMeasFrame {
  std::uint16_t seq = 0;
  std::uint8_t index = 0;    ///< position within the epoch, 0..n_meas-1
  fsw::GnssRawMeasurement meas{};
};

CodecStatus decode_imu(const CanFrame& f, ImuFrame& out);
CodecStatus decode_gps_epoch(const CanFrame& f, GpsEpochFrame& out);
CodecStatus decode_gps_meas(const CanFrame& f, GpsMeasFrame& out);
CodecStatus decode_gps_almanac(const CanFrame& f, fsw::GpsAlmanac& out);

// ---- lockstep flow control (HIL) ---------------------------------------------------------------
enum class SimCommand : std::uint8_t { kStart = 1, kEnd = 2 };
enum class SimMode : std::uint8_t { kLockstep = 0, kRealtime = 1 };
/// SIM_CONTROL, bus simulator -> flight software. Start: the planned run (steps = GPS intervals,
/// imu_samples = IMU samples; frames = 0); the simulator repeats it until an FSW_ACK with its
/// run_id answers. End: what was actually sent before it (steps, IMU_SAMPLE frames, data frames).
struct SimControlFrame {
  SimCommand command = SimCommand::kStart;
  SimMode mode = SimMode::kLockstep;
  std::uint16_t window_imu = 0;  ///< lockstep: IMU samples the simulator may run ahead of the last ack
  std::uint32_t run_id = 0;      ///< chosen by the simulator, echoed in FSW_ACK (non-zero)
  std::uint64_t seed = 0;        ///< the scenario seed of the run
  std::uint32_t steps = 0;
  std::uint32_t imu_samples = 0;
  std::uint32_t frames = 0;
};
/// FSW_ACK flags.
enum FswAckFlag : std::uint8_t {
  kAckInitialised = 1u << 0,  ///< the flight software has initialised (navigating)
  kAckEndReceived = 1u << 1,  ///< the run's SIM_CONTROL end was received: these are the final counts
};
/// FSW_ACK, flight software -> bus simulator: counts since the SIM_CONTROL start of run_id.
struct FswAckFrame {
  std::uint32_t run_id = 0;        ///< 0: no run started yet
  std::uint32_t imu_frames = 0;    ///< IMU_SAMPLE frames taken from the bus, length and CRC right (delivered or rejected on content)
  std::uint32_t frames = 0;        ///< data frames with a known ID, right length and CRC (control frames excluded)
  std::uint32_t imu_delivered = 0; ///< IMU samples handed to the flight software
  std::uint32_t nav_frames = 0;    ///< navigation frames computed
  std::uint8_t flags = 0;          ///< FswAckFlag
};
/// kBadInput for a command or mode outside the enums (no frame made).
CodecStatus encode_sim_control(const SimControlFrame& c, CanFrame& out);
/// kBadInput for a command or mode outside the enums (the other fields are still decoded).
CodecStatus decode_sim_control(const CanFrame& f, SimControlFrame& out);
void encode_fsw_ack(const FswAckFrame& a, CanFrame& out);
CodecStatus decode_fsw_ack(const CanFrame& f, FswAckFrame& out);

/// IMU encoder with the rounding residual carried to the next sample (as integrating IMUs do):
/// the sum of the transmitted increments differs from the sum of the true ones by less than one
/// LSB at every sample, so quantization never accumulates into an angle or velocity drift.
/// The sample counter advances by one per encode() call, including rejected samples, so a
/// receiver sees a sample the encoder could not send as a counter gap.
class ImuEncoder {
 public:
  explicit ImuEncoder(std::uint32_t first_counter = 0) : counter_(first_counter) {}
  /// extra_status: kImuGyroFail / kImuAccelFail from the IMU's own monitoring.
  /// kOk; kFlagged (non-finite increments: zeros with kImuSampleInvalid, residual kept);
  /// kBadInput (non-finite t_s, dt_s <= 0 or non-finite: no frame); kOutOfRange (time tag or dt
  /// outside the fields: no frame). Saturated components are clamped and flagged, and their
  /// residual restarts from 0.
  CodecStatus encode(const fsw::ImuSample& s, CanFrame& out, std::uint16_t extra_status = 0);
  std::uint32_t next_counter() const { return counter_; }
  /// Residual carried to the next sample, in LSB, [-0.5, 0.5] per component.
  const double* dtheta_residual_lsb() const { return res_dtheta_; }
  const double* dv_residual_lsb() const { return res_dv_; }

 private:
  std::uint32_t counter_;
  double res_dtheta_[3] = {0.0, 0.0, 0.0};
  double res_dv_[3] = {0.0, 0.0, 0.0};
};

/// One receiver epoch -> GPS_EPOCH + one GPS_MEAS per measurement, with the epoch sequence number
/// advancing per epoch. Measurements that cannot be represented (non-finite, outside a field's
/// range, PRN 0) are left out and the header announces only the ones sent.
class GpsEncoder {
 public:
  static constexpr int kMaxFrames = 1 + fsw::kMaxGnssChannels;
  explicit GpsEncoder(std::uint16_t first_seq = 0) : seq_(first_seq) {}
  /// out must hold kMaxFrames frames; n_out receives the number made, n_skipped the measurements
  /// left out. kBadInput / kOutOfRange (no frames) when the header itself is not representable
  /// (non-finite t_s, week outside 0..65535, tow outside [0, 604800) s, n_meas outside 0..16).
  CodecStatus encode(const fsw::GnssRawEpoch& epoch, CanFrame* out, int& n_out, int& n_skipped);
  std::uint16_t next_seq() const { return seq_; }

 private:
  std::uint16_t seq_;
};

/// The single-frame encoders GpsEncoder is made of (tests use them to craft frames).
CodecStatus encode_gps_epoch(std::uint16_t seq, int gps_week, double gps_tow_s, double t_s, int n_meas,
                             std::uint8_t status, CanFrame& out);
CodecStatus encode_gps_meas(std::uint16_t seq, int index, const fsw::GnssRawMeasurement& m, CanFrame& out);
/// kOutOfRange for elements outside the fields (eccentricity >= 0.5, sqrt(A) >= 8192, ...);
/// angles are sent modulo 2 pi in [-pi, pi) (the orbit is unchanged).
CodecStatus encode_gps_almanac(const fsw::GpsAlmanac& a, CanFrame& out);
/// Writes the CRC into the last two bytes (for tests that craft frames with chosen contents).
void seal_frame(CanFrame& f);

/// One simulator step -> frames in bus order: the IMU samples, then the GPS epoch (header first),
/// then almanac frames. The building block of the bus side of SIL/HIL (one encoder per bus, so
/// that the IMU residual and the counters run continuously).
class CanStepEncoder {
 public:
  struct Result {
    int n_frames = 0;
    int imu_rejected = 0;    ///< samples that made no frame (kBadInput / kOutOfRange)
    int imu_flagged = 0;     ///< samples sent flagged unusable
    int gps_skipped = 0;     ///< measurements left out
    int gps_rejected = 0;    ///< 1 when the epoch header could not be encoded
    int almanac_rejected = 0;
  };
  /// Frames needed at most for a step of n_imu samples, an epoch and n_alm almanac entries.
  static constexpr int max_frames(int n_imu, int n_alm) { return n_imu + GpsEncoder::kMaxFrames + n_alm; }
  /// out must hold max_frames(n_imu, n_alm) frames.
  Result encode(const fsw::ImuSample* imu, int n_imu, const fsw::GnssRawEpoch* epoch, const fsw::GpsAlmanac* alm,
                int n_alm, CanFrame* out);
  ImuEncoder& imu() { return imu_; }
  GpsEncoder& gps() { return gps_; }

 private:
  ImuEncoder imu_;
  GpsEncoder gps_;
};

/// Duration of a CAN FD frame on the wire [s], with worst-case bit stuffing, for a nominal
/// (arbitration) and a data bit rate (ISO 11898-1:2015 frame format, 11-bit identifier, BRS).
double can_fd_frame_time_s(int payload_len, double nominal_bps, double data_bps);
/// Duration of a classic CAN frame (11-bit identifier) with worst-case bit stuffing [s].
double can_classic_frame_time_s(int payload_len, double bps);

}  // namespace hal::can
