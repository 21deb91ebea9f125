// CanRxAssembler: the clean stream comes through complete and unchanged; every kind of bad input
// is counted under its reason while the valid frames around it are still delivered.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "hal/can_protocol.hpp"
#include "hal/can_rx_assembler.hpp"
#include "sim/scenario.hpp"
#include "sim/sensor_stream.hpp"

namespace {

using hal::CanFrame;
using hal::CanRxAssembler;
using hal::CanRxHealth;
using namespace hal::can;

/// A few seconds of the simulator's bus traffic, frames in bus order.
struct Traffic {
  std::vector<CanFrame> frames;
  std::vector<fsw::ImuSample> imu;         ///< decoded IMU samples in order
  std::vector<fsw::GnssRawEpoch> epochs;   ///< raw epochs as the simulator made them
  std::vector<fsw::GpsAlmanac> almanac;
};

Traffic make_traffic(double duration_s) {
  sim::Scenario sc;
  sc.duration_s = duration_s;
  sim::SensorStream stream(sc);
  Traffic t;
  t.almanac = stream.almanac();
  CanStepEncoder enc;
  sim::SensorStep step;
  bool first = true;
  while (stream.next(step)) {
    const int n_alm = first ? static_cast<int>(t.almanac.size()) : 0;
    std::vector<CanFrame> out(static_cast<std::size_t>(CanStepEncoder::max_frames(static_cast<int>(step.imu.size()), n_alm)));
    const CanStepEncoder::Result r = enc.encode(step.imu.data(), static_cast<int>(step.imu.size()),
                                                step.has_epoch ? &step.epoch : nullptr, t.almanac.data(), n_alm, out.data());
    out.resize(static_cast<std::size_t>(r.n_frames));
    for (const CanFrame& f : out) {
      ImuFrame d;
      if (decode_imu(f, d) == CodecStatus::kOk) t.imu.push_back(d.sample);
    }
    t.frames.insert(t.frames.end(), out.begin(), out.end());
    if (step.has_epoch) t.epochs.push_back(step.epoch);
    first = false;
  }
  return t;
}

struct Collected {
  std::vector<fsw::ImuSample> imu;
  std::vector<fsw::GnssRawEpoch> gps;
  std::vector<fsw::GpsAlmanac> alm;
};

void drain(CanRxAssembler& rx, Collected& c) {
  fsw::ImuSample s;
  while (rx.pop_imu(s)) c.imu.push_back(s);
  fsw::GnssRawEpoch e;
  while (rx.pop_gps(e)) c.gps.push_back(e);
  fsw::GpsAlmanac a;
  while (rx.pop_almanac(a)) c.alm.push_back(a);
}

Collected feed(CanRxAssembler& rx, const std::vector<CanFrame>& frames, bool flush = true) {
  Collected c;
  for (const CanFrame& f : frames) {
    rx.push(f, 0.0);
    drain(rx, c);
  }
  if (flush) rx.flush();
  drain(rx, c);
  return c;
}

bool same_bits(const fsw::ImuSample& a, const fsw::ImuSample& b) {
  return std::memcmp(&a.t_s, &b.t_s, sizeof(double)) == 0 && std::memcmp(&a.dt_s, &b.dt_s, sizeof(double)) == 0 &&
         std::memcmp(a.dtheta_rad.data(), b.dtheta_rad.data(), 3 * sizeof(double)) == 0 &&
         std::memcmp(a.dv_mps.data(), b.dv_mps.data(), 3 * sizeof(double)) == 0;
}

std::vector<CanFrame> only(const std::vector<CanFrame>& in, std::uint32_t id) {
  std::vector<CanFrame> out;
  for (const CanFrame& f : in)
    if (f.id == id) out.push_back(f);
  return out;
}

CanFrame imu_frame(std::uint32_t counter, double t_s) {
  ImuEncoder enc(counter);
  fsw::ImuSample s;
  s.t_s = t_s;
  s.dt_s = 1e-3;
  s.dv_mps = fsw::Vec3(0.0, 0.0, -9.81e-3);
  CanFrame f;
  EXPECT_EQ(enc.encode(s, f), CodecStatus::kOk);
  return f;
}

std::vector<CanFrame> epoch_frames(std::uint16_t seq, int n_meas, double t_s = 1.0) {
  fsw::GnssRawEpoch e;
  e.t_s = t_s;
  e.gps_week = 1455;
  e.gps_tow_s = 589825.0;
  e.n_meas = n_meas;
  for (int i = 0; i < n_meas; ++i)
    e.meas[static_cast<std::size_t>(i)] = {static_cast<std::uint8_t>(i + 1), 2.1e7 + 1000.0 * i, -100.0 + i, 40.0};
  GpsEncoder enc(seq);
  CanFrame f[GpsEncoder::kMaxFrames];
  int n = 0, skipped = 0;
  EXPECT_EQ(enc.encode(e, f, n, skipped), CodecStatus::kOk);
  return std::vector<CanFrame>(f, f + n);
}

TEST(CanRxAssembler, CleanStreamIsDeliveredCompleteAndBitIdentical) {
  const Traffic t = make_traffic(3.0);
  CanRxAssembler rx;
  const Collected c = feed(rx, t.frames);
  const CanRxHealth& h = rx.health();
  EXPECT_EQ(h.rejections(), 0u);
  EXPECT_EQ(h.frames, t.frames.size());
  ASSERT_EQ(c.imu.size(), 3000u);
  for (std::size_t i = 0; i < c.imu.size(); ++i) ASSERT_TRUE(same_bits(c.imu[i], t.imu[i])) << i;
  ASSERT_EQ(c.gps.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(c.gps[k].n_meas, t.epochs[k].n_meas);
    EXPECT_EQ(c.gps[k].gps_week, t.epochs[k].gps_week);
    EXPECT_NEAR(c.gps[k].gps_tow_s, t.epochs[k].gps_tow_s, 1e-9);
    for (int i = 0; i < c.gps[k].n_meas; ++i) {
      EXPECT_EQ(c.gps[k].meas[static_cast<std::size_t>(i)].prn, t.epochs[k].meas[static_cast<std::size_t>(i)].prn);
      EXPECT_NEAR(c.gps[k].meas[static_cast<std::size_t>(i)].pseudorange_m,
                  t.epochs[k].meas[static_cast<std::size_t>(i)].pseudorange_m, 0.5e-4 + 1e-8);
    }
  }
  EXPECT_EQ(c.alm.size(), t.almanac.size());
  EXPECT_EQ(h.gps_epochs_delivered, 3u);
  EXPECT_EQ(h.almanac_delivered, t.almanac.size());
  // A second consumer of the same frames gets bit-identical inputs.
  CanRxAssembler rx2;
  const Collected c2 = feed(rx2, t.frames);
  ASSERT_EQ(c2.imu.size(), c.imu.size());
  for (std::size_t i = 0; i < c.imu.size(); ++i) ASSERT_TRUE(same_bits(c.imu[i], c2.imu[i]));
  ASSERT_EQ(c2.gps.size(), c.gps.size());
  EXPECT_EQ(std::memcmp(&c.gps[0].gps_tow_s, &c2.gps[0].gps_tow_s, sizeof(double)), 0);
}

TEST(CanRxAssembler, UnknownIdsWrongLengthsAndCorruptionAreCountedAndNeighboursDelivered) {
  std::vector<CanFrame> in;
  for (std::uint32_t k = 0; k < 10; ++k) in.push_back(imu_frame(k, 1e-3 * (k + 1)));
  CanFrame unknown = in[0];
  unknown.id = 0x123;
  CanFrame ext = in[0];
  ext.extended = true;  // 0x010 as a 29-bit ID is not ours
  CanFrame short_f = in[3];
  short_f.len = 32;     // wrong DLC for IMU_SAMPLE
  CanFrame corrupt = in[5];
  corrupt.data[18] ^= 0x10;  // payload bit flip: CRC mismatch
  CanFrame classic = in[0];
  classic.fd = false;   // a 48-byte classic frame cannot exist
  classic.brs = false;
  std::vector<CanFrame> stream = {in[0], unknown, in[1], ext, in[2], short_f, in[3], in[4], corrupt,
                                  in[5], classic, in[6], in[7], in[8], in[9]};
  CanRxAssembler rx;
  const Collected c = feed(rx, stream);
  const CanRxHealth& h = rx.health();
  EXPECT_EQ(h.unknown_id, 2u);
  EXPECT_EQ(h.bad_length, 1u);
  EXPECT_EQ(h.bad_crc, 1u);
  EXPECT_EQ(h.unsupported_frame, 1u);
  EXPECT_EQ(h.imu_missing, 0u);
  EXPECT_EQ(c.imu.size(), 10u);  // no valid frame dropped
  EXPECT_EQ(h.imu_delivered, 10u);
}

TEST(CanRxAssembler, CounterGapsDuplicatesOutOfOrderAndRestarts) {
  // An IMU that has been running for a while (counter 200000 on) is restarted (counter 0).
  std::vector<CanFrame> in;
  for (std::uint32_t k = 0; k < 40; ++k) in.push_back(imu_frame(200000 + k, 200.0 + 1e-3 * k));
  // 0..9, (10..14 lost), 15..19, 19 again, 21, 20 (late), 22..39, then a restart at counter 0.
  std::vector<CanFrame> stream(in.begin(), in.begin() + 10);
  stream.insert(stream.end(), in.begin() + 15, in.begin() + 20);
  stream.push_back(in[19]);
  stream.push_back(in[21]);
  stream.push_back(in[20]);
  stream.insert(stream.end(), in.begin() + 22, in.end());
  for (std::uint32_t k = 0; k < 3; ++k) stream.push_back(imu_frame(k, 1000.0 + 1e-3 * k));
  // Counter far ahead of the stream is also taken as a restart.
  stream.push_back(imu_frame(4000000000u, 2000.0));
  CanRxAssembler rx;
  const Collected c = feed(rx, stream);
  const CanRxHealth& h = rx.health();
  EXPECT_EQ(h.imu_gaps, 2u);        // 10..14 and 20 (skipped when 21 arrived)
  EXPECT_EQ(h.imu_missing, 6u);
  EXPECT_EQ(h.imu_duplicate, 1u);   // the second 19
  EXPECT_EQ(h.imu_out_of_order, 1u);  // 20 after 21: too late to deliver in time order
  EXPECT_EQ(h.imu_resync, 2u);
  EXPECT_EQ(c.imu.size(), 10u + 5u + 1u + 18u + 3u + 1u);
  // Delivered in strictly increasing time within each run of the counter.
  for (std::size_t i = 1; i < 34; ++i) EXPECT_GT(c.imu[i].t_s, c.imu[i - 1].t_s);
}

TEST(CanRxAssembler, FlaggedImplausibleSaturatedAndTimeMismatchedSamples) {
  ImuEncoder enc;
  std::vector<CanFrame> stream;
  auto add = [&](fsw::ImuSample s, std::uint16_t extra = 0) {
    CanFrame f;
    const CodecStatus st = enc.encode(s, f, extra);
    ASSERT_TRUE(st == CodecStatus::kOk || st == CodecStatus::kFlagged);
    stream.push_back(f);
  };
  fsw::ImuSample s;
  s.dt_s = 1e-3;
  for (int k = 1; k <= 3; ++k) {
    s.t_s = 1e-3 * k;
    add(s);
  }
  s.t_s = 4e-3;
  s.dtheta_rad(0) = std::nan("");  // flagged invalid by the encoder
  add(s);
  s.dtheta_rad(0) = 0.0;
  s.t_s = 5e-3;
  add(s, kImuAccelFail);            // IMU BIT failure
  s.t_s = 6e-3;
  s.dv_mps(2) = -5.0;               // saturates: delivered, counted
  add(s);
  s.dv_mps(2) = 0.0;
  s.t_s = 7.5e-3;                   // time tag 0.5 ms off the counter's grid
  add(s);
  s.t_s = 8.5e-3;
  add(s);
  // Absurd content with a valid CRC: dt = 0 and a 1 ns dt (rates of 1e7 rad/s).
  CanFrame bad = stream.back();
  bad.data[0] = 8;  // counter 8
  std::memset(&bad.data[12], 0, 4);
  seal_frame(bad);
  stream.push_back(bad);
  CanFrame bad2 = bad;
  bad2.data[0] = 9;
  bad2.data[12] = 1;
  bad2.data[18] = 0x01;  // dtheta x = 65536 LSB = 6.6e-7 rad over 1 ns: 655 rad/s
  seal_frame(bad2);
  stream.push_back(bad2);
  s.t_s = 10.5e-3;
  s.dt_s = 1e-3;
  ImuEncoder tail(10);
  CanFrame last;
  ASSERT_EQ(tail.encode(s, last), CodecStatus::kOk);
  stream.push_back(last);

  CanRxAssembler rx;
  const Collected c = feed(rx, stream);
  const CanRxHealth& h = rx.health();
  EXPECT_EQ(h.imu_flagged, 2u);
  EXPECT_EQ(h.imu_saturated, 1u);
  EXPECT_EQ(h.imu_implausible, 2u);
  // The step from 6 ms to 7.5 ms, and the 1 ns "dt" frame (8.5 ms + 1 ns expected, 8.5 ms sent).
  EXPECT_EQ(h.imu_time_mismatch, 2u);
  EXPECT_EQ(h.imu_missing, 0u);        // flagged and implausible samples take their counter slots
  EXPECT_EQ(c.imu.size(), 3u + 1u + 2u + 1u);
  for (const fsw::ImuSample& x : c.imu) EXPECT_TRUE(x.dtheta_rad.allFinite());
}

TEST(CanRxAssembler, GpsEpochsWithZeroAndOneSatelliteAreDelivered) {
  std::vector<CanFrame> stream = epoch_frames(0, 0, 1.0);
  const std::vector<CanFrame> one = epoch_frames(1, 1, 2.0);
  stream.insert(stream.end(), one.begin(), one.end());
  const std::vector<CanFrame> many = epoch_frames(2, 9, 3.0);
  stream.insert(stream.end(), many.begin(), many.end());
  CanRxAssembler rx;
  const Collected c = feed(rx, stream, false);
  ASSERT_EQ(c.gps.size(), 3u);  // all complete without a flush
  EXPECT_EQ(c.gps[0].n_meas, 0);
  EXPECT_EQ(c.gps[1].n_meas, 1);
  EXPECT_EQ(c.gps[2].n_meas, 9);
  EXPECT_EQ(rx.health().gps_epochs_empty, 1u);
  EXPECT_EQ(rx.health().gps_epochs_single, 1u);
  EXPECT_EQ(rx.health().rejections(), 0u);
}

TEST(CanRxAssembler, IncompleteEpochsAreFlushedByTheNextEpochOrTheTimeout) {
  std::vector<CanFrame> e0 = epoch_frames(10, 5, 1.0);
  e0.erase(e0.begin() + 3);  // measurement index 2 lost
  const std::vector<CanFrame> e1 = epoch_frames(11, 4, 2.0);
  CanRxAssembler rx;
  Collected c;
  for (const CanFrame& f : e0) rx.push(f, 100.0);
  drain(rx, c);
  EXPECT_TRUE(c.gps.empty());  // still waiting for index 2
  for (const CanFrame& f : e1) rx.push(f, 100.2);  // within the 0.5 s epoch timeout
  drain(rx, c);
  ASSERT_EQ(c.gps.size(), 2u);
  EXPECT_EQ(c.gps[0].n_meas, 4);  // delivered without the lost one
  EXPECT_EQ(c.gps[0].meas[2].prn, 4);
  EXPECT_EQ(c.gps[1].n_meas, 4);
  EXPECT_EQ(rx.health().gps_epochs_incomplete, 1u);
  EXPECT_EQ(rx.health().gps_meas_missing, 1u);

  // The last epoch of a stream that goes silent: flushed by the timeout.
  std::vector<CanFrame> e2 = epoch_frames(12, 3, 3.0);
  e2.pop_back();
  for (const CanFrame& f : e2) rx.push(f, 102.0);
  rx.poll(102.3);
  drain(rx, c);
  EXPECT_EQ(c.gps.size(), 2u);
  rx.poll(102.6);  // default timeout 0.5 s
  drain(rx, c);
  ASSERT_EQ(c.gps.size(), 3u);
  EXPECT_EQ(c.gps[2].n_meas, 2);
  EXPECT_EQ(rx.health().gps_epochs_timeout, 1u);
  EXPECT_EQ(rx.health().gps_meas_missing, 2u);
}

TEST(CanRxAssembler, GpsReorderingDuplicatesLateAndHeaderlessFrames) {
  std::vector<CanFrame> e0 = epoch_frames(0, 3, 1.0);
  const std::vector<CanFrame> e1 = epoch_frames(1, 3, 2.0);
  std::vector<CanFrame> e2 = epoch_frames(2, 2, 3.0);
  const std::vector<CanFrame> e3 = epoch_frames(3, 2, 4.0);
  std::vector<CanFrame> s;
  // Epoch 0: measurements before the header, one duplicated.
  s.push_back(e0[2]);
  s.push_back(e0[1]);
  s.push_back(e0[1]);
  s.push_back(e0[0]);
  s.push_back(e0[3]);
  // Epoch 1 complete, then a late duplicate of epoch 0's header and a late measurement of epoch 0.
  s.insert(s.end(), e1.begin(), e1.end());
  s.push_back(e0[0]);
  s.push_back(e0[2]);
  // Epoch 2: header lost, its measurements arrive; then epoch 3.
  s.push_back(e2[1]);
  s.push_back(e2[2]);
  s.insert(s.end(), e3.begin(), e3.end());
  CanRxAssembler rx;
  const Collected c = feed(rx, s);
  const CanRxHealth& h = rx.health();
  ASSERT_EQ(c.gps.size(), 3u);  // epochs 0, 1, 3
  EXPECT_EQ(c.gps[0].n_meas, 3);
  EXPECT_EQ(c.gps[0].meas[0].prn, 1);  // back in index order
  EXPECT_EQ(c.gps[2].t_s, 4.0);
  EXPECT_EQ(h.gps_duplicate, 1u);       // the repeated measurement inside epoch 0
  EXPECT_EQ(h.gps_out_of_order, 2u);    // epoch 0's header and measurement after epoch 1 finished
  EXPECT_EQ(h.gps_headerless, 1u);
  EXPECT_EQ(h.gps_meas_orphaned, 2u);
  // Duplicates of the last finished epoch are recognised as such.
  CanRxAssembler rx2;
  std::vector<CanFrame> s2 = e3;
  s2.push_back(e3[0]);
  s2.push_back(e3[1]);
  feed(rx2, s2);
  EXPECT_EQ(rx2.health().gps_duplicate, 2u);
  EXPECT_EQ(rx2.health().gps_out_of_order, 0u);
}

TEST(CanRxAssembler, ImplausibleGpsValuesAndInvalidAlmanac) {
  std::vector<CanFrame> e0 = epoch_frames(5, 3, 1.0);
  // Measurement 1: PRN 0 (impossible) with a valid CRC.
  e0[2].data[3] = 0;
  seal_frame(e0[2]);
  // Header with 17 measurements announced.
  std::vector<CanFrame> e1 = epoch_frames(6, 1, 2.0);
  e1[0].data[20] = 17;
  seal_frame(e1[0]);
  // Header without the time-valid flag.
  std::vector<CanFrame> e2 = epoch_frames(7, 0, 3.0);
  e2[0].data[21] = 0;
  seal_frame(e2[0]);
  std::vector<CanFrame> e3 = epoch_frames(8, 2, 4.0);
  // Pseudorange of 1 km (absurd for GPS).
  fsw::GnssRawMeasurement m{9, 1000.0, 10.0, 40.0};
  ASSERT_EQ(encode_gps_meas(8, 1, m, e3[2]), CodecStatus::kOk);
  std::vector<CanFrame> s = e0;
  s.insert(s.end(), e1.begin(), e1.end());
  s.insert(s.end(), e2.begin(), e2.end());
  s.insert(s.end(), e3.begin(), e3.end());
  // Almanac: a valid one, one that fsw::almanac_valid rejects (sqrt(A) = 100 m^0.5).
  fsw::GpsAlmanac a;
  a.prn = 3;
  a.eccentricity = 0.01;
  a.toa_s = 589824.0;
  a.inclination_rad = 0.95;
  a.sqrt_a_sqrtm = 5153.6;
  a.week_mod_1024 = 431;
  CanFrame fa;
  ASSERT_EQ(encode_gps_almanac(a, fa), CodecStatus::kOk);
  s.push_back(fa);
  a.sqrt_a_sqrtm = 100.0;
  ASSERT_EQ(encode_gps_almanac(a, fa), CodecStatus::kOk);
  s.push_back(fa);
  CanRxAssembler rx;
  const Collected c = feed(rx, s);
  const CanRxHealth& h = rx.health();
  EXPECT_EQ(h.gps_meas_implausible, 2u);
  EXPECT_EQ(h.gps_epoch_implausible, 2u);
  ASSERT_EQ(c.gps.size(), 2u);  // epoch 5 (complete, 2 usable) and epoch 8 (1 usable)
  EXPECT_EQ(c.gps[0].n_meas, 2);
  EXPECT_EQ(c.gps[1].n_meas, 1);
  EXPECT_EQ(h.gps_epochs_incomplete, 0u);
  EXPECT_EQ(h.gps_headerless, 1u);  // epoch 6's measurement without its (rejected) header
  EXPECT_EQ(h.almanac_delivered, 1u);
  EXPECT_EQ(h.almanac_invalid, 1u);
  ASSERT_EQ(c.alm.size(), 1u);
  EXPECT_EQ(c.alm[0].prn, 3);
}

TEST(CanRxAssembler, FullQueuesCountWhatIsLost) {
  CanRxAssembler rx;
  for (std::uint32_t k = 0; k < 300; ++k) rx.push(imu_frame(k, 1e-3 * (k + 1)), 0.0);
  EXPECT_EQ(rx.imu_pending(), CanRxAssembler::kImuQueue);
  EXPECT_EQ(rx.health().queue_overflow, 300u - CanRxAssembler::kImuQueue);
  EXPECT_EQ(rx.health().imu_delivered, static_cast<std::uint32_t>(CanRxAssembler::kImuQueue));
}

TEST(CanRxAssembler, CounterNamesCoverEveryField) {
  // for_each lists every counter once: the struct is made of uint32 counters only.
  int n = 0;
  CanRxHealth h;
  h.for_each([&n](const char*, std::uint32_t) { ++n; });
  EXPECT_EQ(static_cast<std::size_t>(n) * sizeof(std::uint32_t), sizeof(CanRxHealth));
}

}  // namespace
