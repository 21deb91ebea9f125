// The one wiring list: which harness feeds the flight application from which event source,
// through which driver, watched by which observers (fsw/driver.hpp: drive(source, driver,
// observer)). README.md's harness table ("Architecture: one data path") is this list, row for
// row, and tests/unit/test_harness_wiring.cpp checks both ways: the README table against the
// list, and each entry against its file (the file calls fsw::drive with the named source and
// driver), and that no other file of tools/, hal/ or fsw/baremetal calls fsw::drive.
#pragma once

#include <array>
#include <string_view>

namespace tools {

struct HarnessWiring {
  std::string_view harness;    ///< the command or build
  std::string_view file;       ///< where it calls fsw::drive (relative to the source tree)
  std::string_view source;     ///< the event source's type, as named in that file
  std::string_view feeds;      ///< what the source delivers
  std::string_view driver;     ///< the owner of the FlightApp: hal::FswNode or fsw::FlightDriver
  std::string_view layouts;    ///< the layouts it flies
  std::string_view observers;  ///< what watches the FrameOutput
};

inline constexpr std::array<HarnessWiring, 9> kHarnessWiring{{
    {"`sdins sil`", "tools/sdins/cmd_sil.cpp", "hal::CanFswInput",
     "the simulated sensor stream (`sim::SensorStream`) encoded into CAN frames in-process and decoded by the "
     "receive assembler",
     "hal::FswNode", "15Full, 24Full", "the node's: input log, LCM telemetry, digest, 1 Hz thread"},
    {"HIL (`sdins bus-sim` + `sdins fsw`)", "tools/run/src/hil.cpp", "hal::CanFswInput",
     "the same stream on a CAN bus (udp, SocketCAN)", "hal::FswNode", "15Full, 24Full",
     "the node's; FSW_ACK; real time: each minor frame's execution"},
    {"`sdins replay`", "tools/sdins/cmd_replay.cpp", "hal::LcmReplayReader",
     "an LCM log in time order, less the GNSS the configuration does not take and `--outages`", "hal::FswNode",
     "15Full, 24Full", "the node's"},
    {"`sdins montecarlo`, `sdins paper`", "tools/run/src/montecarlo.cpp", "fsw::EventBatch",
     "per run a `sim::SensorStream` on the shared truth track, read one minor frame at a time into a batch that "
     "every model runs over",
     "fsw::FlightDriver", "15, 24, 15Conv or 15Full, 24Full", "`FlightAppRunner`: truth scoring at every epoch"},
    {"`sdins audit timing`", "tools/audit/src/timing_audit.cpp", "sim::SensorStream",
     "the Monte Carlo's stream, run 0's seed", "fsw::FlightDriver", "15, 24, 15Full, 24Full",
     "`FrameTimer`: every call timed, the 1 Hz group run apart"},
    {"`sdins diagnose`", "tools/diagnosis/src/diagnosis_model.cpp", "tools::RecordedSource",
     "a recording in memory (`tools::RecordedData`), less the GNSS not taken and the outage windows",
     "fsw::FlightDriver", "Diag", "the scoring: innovations, navigation error, outages"},
    {"`sdins diagnose`: the mounting from the direction of travel", "tools/diagnosis/src/diagnosis_mounting.cpp",
     "tools::RecordedSource", "the same recording in memory, less the GNSS not taken", "fsw::FlightDriver", "Diag",
     "the velocity in the IMU's axes and the attitude sigma at each epoch at speed"},
    {"target replay (`sdins audit target`: QEMU image, host `sdins_target`)", "fsw/baremetal/replay.cpp",
     "RecordedInput", "a recorded input read from the board", "fsw::FlightDriver", "15Full, 24Full",
     "`Model`: output lines, digest, tick counts, the 1 Hz group run apart"},
    {"bare-metal image", "fsw/baremetal/main.cpp", "SyntheticSensors", "a synthetic receiver at rest",
     "fsw::FlightDriver", "15, 24", "debugger-visible globals"},
}};

}  // namespace tools
