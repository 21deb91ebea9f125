// HIL lockstep: the SIM_CONTROL / FSW_ACK frames, CanFswInput's handling of them, and the bus
// simulator and flight software loops (tools/hil.hpp) on two threads over a loop: bus, whose
// navigation must be bit-identical to the in-process path (SensorStream -> CanStepEncoder ->
// CanFswInput -> FswNode without a bus).
#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <thread>
#include <vector>

#include "fsw/driver.hpp"
#include "hal/can_bus.hpp"
#include "hal/can_fsw_input.hpp"
#include "hal/can_protocol.hpp"
#include "hal/can_rx_assembler.hpp"
#include "hal/fsw_node.hpp"
#include "cfg/flight_config.hpp"
#include "tools/hil.hpp"
#include "tools/step_producer.hpp"
#include "sim/sensor_stream.hpp"

namespace {

using hal::CanFrame;
namespace can = hal::can;

hal::FswNodeConfig node_config() {
  hal::FswNodeConfig c;
  c.app = cfg::shipped_flight_config().app;  // config/default.toml, as `sdins sil` / `fsw` fly
  c.telemetry.lcm_url = "none";
  return c;
}

sim::Scenario short_scenario(double duration_s, std::uint64_t seed) {
  sim::Scenario sc;
  sc.duration_s = duration_s;
  sc.seed = seed;
  return sc;
}

/// The reference: the same frames straight into CanFswInput, no bus, no threads.
hal::FswNodeSummary in_process(const sim::Scenario& sc) {
  sim::SensorStream stream(sc, sc.seed);
  hal::FswNode node;
  std::string err;
  EXPECT_TRUE(node.open(node_config(), err)) << err;
  hal::CanFswInput in(node.summary());
  can::CanStepEncoder enc;
  sim::SensorStep step;
  bool first = true;
  std::vector<CanFrame> out;
  while (stream.next(step)) {
    const int na = first ? static_cast<int>(stream.almanac().size()) : 0;
    out.resize(static_cast<std::size_t>(can::CanStepEncoder::max_frames(static_cast<int>(step.imu.size()), na)));
    const auto r = enc.encode(step.imu.data(), static_cast<int>(step.imu.size()), step.has_epoch ? &step.epoch : nullptr,
                              stream.almanac().data(), na, out.data());
    for (int i = 0; i < r.n_frames; ++i) {
      in.push(out[static_cast<std::size_t>(i)], 0.0);
      fsw::drive(in, node);
    }
    first = false;
  }
  in.finish();
  fsw::drive(in, node);
  EXPECT_EQ(in.health().rejections(), 0u);
  return node.summary();
}

can::SimControlFrame control(can::SimCommand cmd, std::uint32_t run_id) {
  can::SimControlFrame c;
  c.command = cmd;
  c.mode = can::SimMode::kLockstep;
  c.window_imu = 200;
  c.run_id = run_id;
  c.seed = 0x0123456789abcdefull;
  c.steps = 90;
  c.imu_samples = 90000;
  c.frames = cmd == can::SimCommand::kEnd ? 91234u : 0u;
  return c;
}

}  // namespace

TEST(HilProtocol, SimControlAndFswAckRoundTripWithCrc) {
  CanFrame f;
  const can::SimControlFrame c = control(can::SimCommand::kEnd, 0xdeadbeef);
  ASSERT_EQ(can::encode_sim_control(c, f), can::CodecStatus::kOk);
  EXPECT_EQ(f.id, can::kIdSimControl);
  EXPECT_EQ(f.len, can::kLenSimControl);
  EXPECT_TRUE(f.fd && f.brs && !f.extended);
  can::SimControlFrame d;
  ASSERT_EQ(can::decode_sim_control(f, d), can::CodecStatus::kOk);
  EXPECT_EQ(d.command, can::SimCommand::kEnd);
  EXPECT_EQ(d.mode, can::SimMode::kLockstep);
  EXPECT_EQ(d.window_imu, 200);
  EXPECT_EQ(d.run_id, 0xdeadbeefu);
  EXPECT_EQ(d.seed, 0x0123456789abcdefull);
  EXPECT_EQ(d.steps, 90u);
  EXPECT_EQ(d.imu_samples, 90000u);
  EXPECT_EQ(d.frames, 91234u);

  can::FswAckFrame a;
  a.run_id = 7;
  a.imu_frames = 4000000000u;
  a.frames = 123456;
  a.imu_delivered = 3999999999u;
  a.nav_frames = 800000;
  a.flags = can::kAckInitialised | can::kAckEndReceived;
  can::encode_fsw_ack(a, f);
  EXPECT_EQ(f.id, can::kIdFswAck);
  EXPECT_EQ(f.len, can::kLenFswAck);
  can::FswAckFrame b;
  ASSERT_EQ(can::decode_fsw_ack(f, b), can::CodecStatus::kOk);
  EXPECT_EQ(b.run_id, 7u);
  EXPECT_EQ(b.imu_frames, 4000000000u);
  EXPECT_EQ(b.frames, 123456u);
  EXPECT_EQ(b.imu_delivered, 3999999999u);
  EXPECT_EQ(b.nav_frames, 800000u);
  EXPECT_EQ(b.flags, can::kAckInitialised | can::kAckEndReceived);

  CanFrame bad = f;
  bad.data[5] ^= 0x10;
  EXPECT_EQ(can::decode_fsw_ack(bad, b), can::CodecStatus::kBadCrc);
  bad = f;
  bad.len = 20;
  EXPECT_EQ(can::decode_fsw_ack(bad, b), can::CodecStatus::kBadLength);
  // A command outside the enum: not encodable, and a crafted frame decodes as kBadInput.
  can::SimControlFrame x = c;
  x.command = static_cast<can::SimCommand>(9);
  EXPECT_EQ(can::encode_sim_control(x, f), can::CodecStatus::kBadInput);
  ASSERT_EQ(can::encode_sim_control(c, f), can::CodecStatus::kOk);
  f.data[0] = 9;
  can::seal_frame(f);
  EXPECT_EQ(can::decode_sim_control(f, d), can::CodecStatus::kBadInput);
}

TEST(HilProtocol, AssemblerCountsControlFramesAsNoSensorData) {
  hal::CanRxAssembler rx;
  CanFrame f;
  ASSERT_EQ(can::encode_sim_control(control(can::SimCommand::kStart, 1), f), can::CodecStatus::kOk);
  EXPECT_EQ(rx.push(f, 0.0), can::CodecStatus::kOk);
  can::encode_fsw_ack(can::FswAckFrame{}, f);
  EXPECT_EQ(rx.push(f, 0.0), can::CodecStatus::kOk);
  EXPECT_EQ(rx.health().control_frames, 2u);
  EXPECT_EQ(rx.health().unknown_id, 0u);
  EXPECT_EQ(rx.health().rejections(), 0u);
  fsw::ImuSample s;
  EXPECT_FALSE(rx.pop_imu(s));
}

TEST(HilProtocol, CanFswInputTakesControlOutAndIgnoresAcks) {
  hal::FswNode node;
  std::string err;
  ASSERT_TRUE(node.open(node_config(), err)) << err;
  hal::CanFswInput in(node.summary());
  // Every frame as a receiver takes it: pushed, then what it completed delivered to the node.
  const auto push = [&](const CanFrame& frame) {
    in.push(frame, 0.0);
    fsw::drive(in, node);
  };
  EXPECT_FALSE(in.run_started());
  EXPECT_EQ(in.ack().run_id, 0u);

  // Frames before the run: delivered to the node, not counted in the run's ack.
  can::ImuEncoder imu;
  fsw::ImuSample s;
  s.dt_s = 0.001;
  s.dv_mps = fsw::Vec3(0.0, 0.0, -0.0098);
  CanFrame f;
  s.t_s = 0.001;
  ASSERT_EQ(imu.encode(s, f), can::CodecStatus::kOk);
  push(f);

  ASSERT_EQ(can::encode_sim_control(control(can::SimCommand::kStart, 42), f), can::CodecStatus::kOk);
  push(f);
  EXPECT_TRUE(in.run_started());
  EXPECT_TRUE(in.control_changed());
  EXPECT_EQ(in.run().run_id, 42u);
  push(f);  // the simulator repeats its start until answered: not a new run
  EXPECT_FALSE(in.control_changed());

  for (int i = 2; i <= 11; ++i) {
    s.t_s = 0.001 * i;
    ASSERT_EQ(imu.encode(s, f), can::CodecStatus::kOk);
    if (i == 5) f.data[20] ^= 0xFF;  // corrupted IMU frame: rejected, and not acknowledged as the simulator's
    push(f);
    EXPECT_FALSE(in.control_changed());
  }
  // Another flight software's ack, a corrupted SIM_CONTROL, an end of another run.
  can::FswAckFrame other;
  other.run_id = 42;
  other.imu_frames = 99999;
  can::encode_fsw_ack(other, f);
  push(f);
  ASSERT_EQ(can::encode_sim_control(control(can::SimCommand::kEnd, 42), f), can::CodecStatus::kOk);
  CanFrame corrupt = f;
  corrupt.data[9] ^= 1;
  push(corrupt);
  EXPECT_FALSE(in.end_received());
  ASSERT_EQ(can::encode_sim_control(control(can::SimCommand::kEnd, 43), f), can::CodecStatus::kOk);
  push(f);
  EXPECT_FALSE(in.end_received());

  const can::FswAckFrame a = in.ack();
  EXPECT_EQ(a.run_id, 42u);
  EXPECT_EQ(a.imu_frames, 9u);  // the intact ones: bus-sim's end check sees the damaged frame as not taken
  EXPECT_EQ(a.frames, 9u);
  EXPECT_EQ(a.imu_delivered, 9u);
  EXPECT_EQ(a.flags & can::kAckEndReceived, 0);
  EXPECT_EQ(in.foreign_acks(), 1u);
  EXPECT_EQ(in.control_rejected(), 2u);
  EXPECT_EQ(in.control_frames(), 2u);  // the start and its repetition
  // The assembler saw only the IMU frames.
  EXPECT_EQ(in.health().frames, 11u);
  EXPECT_EQ(in.health().bad_crc, 1u);
  EXPECT_EQ(in.health().unknown_id, 0u);
  EXPECT_EQ(in.health().control_frames, 0u);

  ASSERT_EQ(can::encode_sim_control(control(can::SimCommand::kEnd, 42), f), can::CodecStatus::kOk);
  push(f);
  EXPECT_TRUE(in.end_received());
  EXPECT_TRUE(in.control_changed());
  EXPECT_EQ(in.end().frames, 91234u);
  EXPECT_NE(in.ack().flags & can::kAckEndReceived, 0);
}

namespace {

struct HilRun {
  tools::BusSimResult sim;
  tools::FswRunResult fsw;
};

HilRun run_hil_on_loop(const sim::Scenario& sc, const std::string& bus_name, int window) {
  hal::CanBus fsw_bus, sim_bus;
  EXPECT_EQ(fsw_bus.open(bus_name), hal::CanBusStatus::kOk);
  EXPECT_EQ(sim_bus.open(bus_name), hal::CanBusStatus::kOk);
  HilRun out;
  tools::FswRunConfig fc;
  fc.node = node_config();
  fc.idle_timeout_s = 30.0;
  std::thread fsw_thread([&] { out.fsw = tools::run_fsw(fsw_bus, fc); });
  sim::SensorStream stream(sc, sc.seed);
  tools::BusSimConfig bc;
  bc.lockstep = true;
  bc.window_imu = window;
  bc.seed = sc.seed;
  bc.ack_timeout_s = 30.0;
  out.sim = tools::run_bus_sim(sim_bus, stream, bc);
  fsw_thread.join();
  return out;
}

}  // namespace

TEST(HilLockstep, TwoThreadsOverLoopBusGiveTheInProcessDigest) {
  const sim::Scenario sc = short_scenario(12.0, 11);
  const hal::FswNodeSummary ref = in_process(sc);
  ASSERT_TRUE(ref.initialised);
  ASSERT_GT(ref.nav_frames, 1000u);
  // The digest tells runs apart: another seed's navigation differs.
  EXPECT_NE(in_process(short_scenario(12.0, 12)).digest, ref.digest);

  const HilRun h = run_hil_on_loop(sc, "loop:hil-lockstep-digest", 200);
  ASSERT_TRUE(h.sim.ok) << h.sim.error;
  EXPECT_EQ(h.fsw.exit, tools::FswExit::kEndOfRun) << h.fsw.error;
  EXPECT_EQ(h.fsw.summary.digest, ref.digest) << tools::digest_hex(h.fsw.summary.digest) << " vs "
                                              << tools::digest_hex(ref.digest);
  EXPECT_EQ(h.fsw.summary.nav_frames, ref.nav_frames);
  EXPECT_EQ(h.fsw.summary.init_t_s, ref.init_t_s);
  // Flow control: the window held, every frame arrived and was acknowledged.
  EXPECT_LE(h.sim.max_ahead_imu, 200);
  EXPECT_TRUE(h.sim.final_ack);
  EXPECT_EQ(h.sim.imu_sent, 12000);
  EXPECT_EQ(h.fsw.imu_frames, 12000u);
  EXPECT_TRUE(h.fsw.counts_match_end);
  EXPECT_EQ(h.fsw.run.run_id, h.sim.run_id);
  EXPECT_EQ(h.fsw.run.seed, 11u);
  EXPECT_EQ(h.fsw.rx.rejections(), 0u);
  EXPECT_EQ(h.fsw.bus.queue_dropped, 0u);
  EXPECT_EQ(h.sim.steps, 12);
}

TEST(HilLockstep, SmallWindowMakesTheSimulatorWaitAndStillMatches) {
  const sim::Scenario sc = short_scenario(3.0, 5);
  const hal::FswNodeSummary ref = in_process(sc);
  const HilRun h = run_hil_on_loop(sc, "loop:hil-lockstep-window", 7);
  ASSERT_TRUE(h.sim.ok) << h.sim.error;
  EXPECT_EQ(h.fsw.summary.digest, ref.digest);
  EXPECT_LE(h.sim.max_ahead_imu, 7);
  EXPECT_GT(h.sim.window_waits, 0);
  EXPECT_GT(h.sim.acks_received, 3000 / 5 / 2);
}

TEST(HilLockstep, BusSimWithoutFlightSoftwareReportsTheTimeout) {
  hal::CanBus bus;
  ASSERT_EQ(bus.open("loop:hil-nobody"), hal::CanBusStatus::kOk);
  sim::SensorStream stream(short_scenario(2.0, 1));
  tools::BusSimConfig bc;
  bc.ack_timeout_s = 0.3;
  const tools::BusSimResult r = tools::run_bus_sim(bus, stream, bc);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("no flight software answered"), std::string::npos) << r.error;
  EXPECT_EQ(r.imu_sent, 0);
  EXPECT_GE(r.control_sent, 1);
}

TEST(HilLockstep, FlightSoftwareOnASilentBusStopsAtTheIdleTimeout) {
  hal::CanBus bus;
  ASSERT_EQ(bus.open("loop:hil-silent"), hal::CanBusStatus::kOk);
  tools::FswRunConfig fc;
  fc.node = node_config();
  fc.idle_timeout_s = 0.3;
  const tools::FswRunResult r = tools::run_fsw(bus, fc);
  EXPECT_EQ(r.exit, tools::FswExit::kIdleTimeout);
  EXPECT_FALSE(r.run_started);
  EXPECT_EQ(r.frames_received, 0u);
  EXPECT_EQ(r.acks_sent, 0u);
  EXPECT_GE(r.wall_s, 0.3);
}

TEST(StepProducer, GivesTheFramesAndTruthOfEncodingInline) {
  // The producer's thread (sdins sil, sdins bus-sim) against the same stream encoded here: the
  // same frames in the same order, step by step, with the step's truth time and full truth.
  const sim::Scenario sc = short_scenario(12.0, 5);
  sim::SensorStream inline_stream(sc, sc.seed), threaded_stream(sc, sc.seed);
  tools::StepProducer producer(threaded_stream, nullptr);
  can::CanStepEncoder enc;
  sim::SensorStep step;
  tools::EncodedStep got;
  std::vector<CanFrame> want;
  bool first = true;
  int steps = 0;
  while (inline_stream.next(step)) {
    ASSERT_TRUE(producer.next(got)) << "step " << steps;
    const int na = first ? static_cast<int>(inline_stream.almanac().size()) : 0;
    want.resize(static_cast<std::size_t>(can::CanStepEncoder::max_frames(static_cast<int>(step.imu.size()), na)));
    const auto r = enc.encode(step.imu.data(), static_cast<int>(step.imu.size()), step.has_epoch ? &step.epoch : nullptr,
                              inline_stream.almanac().data(), na, want.data());
    first = false;
    ASSERT_EQ(got.frames.size(), static_cast<std::size_t>(r.n_frames)) << "step " << steps;
    for (int i = 0; i < r.n_frames; ++i) {
      const CanFrame& a = got.frames[static_cast<std::size_t>(i)];
      const CanFrame& b = want[static_cast<std::size_t>(i)];
      ASSERT_EQ(a.id, b.id);
      ASSERT_EQ(a.len, b.len);
      ASSERT_EQ(a.data, b.data) << "step " << steps << " frame " << i;
    }
    EXPECT_EQ(got.has_epoch, step.has_epoch);
    EXPECT_EQ(got.truth_t_s, inline_stream.truth().t_s);
    const sim::TruthSample* t = inline_stream.full_truth();
    ASSERT_EQ(got.has_full_truth, t != nullptr);
    if (t != nullptr) {
      EXPECT_EQ(got.full_truth.t_s, t->t_s);
      EXPECT_EQ(got.full_truth.llh, t->llh);
      EXPECT_EQ(got.full_truth.C_b_n, t->C_b_n);
    }
    ++steps;
  }
  EXPECT_FALSE(producer.next(got));
  EXPECT_TRUE(producer.error().empty());
  EXPECT_EQ(steps, 12);
}

TEST(StepProducer, AReaderThatStopsEarlyEndsTheThread) {
  // Destroyed after two of 60 steps, with the producer waiting on a full queue: it ends, no hang.
  const sim::Scenario sc = short_scenario(60.0, 2);
  sim::SensorStream stream(sc, sc.seed);
  {
    tools::StepProducer producer(stream, nullptr);
    tools::EncodedStep s;
    ASSERT_TRUE(producer.next(s));
    ASSERT_TRUE(producer.next(s));
  }
  SUCCEED();
}
