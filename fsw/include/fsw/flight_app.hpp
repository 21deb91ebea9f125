// The flight application: everything between the decoded sensor inputs and the navigation
// output, the same in SIL (simulator in-process), HIL (CAN bus) and replay (LCM log).
//
//   on_almanac(GpsAlmanac)   -> the almanac table (flight code validates every element)
//   on_gnss(GnssRawEpoch)    -> satellite positions from the almanac (gnss_epoch_from_raw); before
//                               initialisation: a single-point solution that may initialise
//   on_gnss_pvt(GnssPvtMeasurement) -> a position/velocity solution (loosely coupled update);
//                               before initialisation: may initialise (land vehicles)
//   on_imu(ImuSample)        -> before initialisation: levelling; after: batched into the
//                               executive's minor frames (the 200 Hz group; it releases the 1 Hz
//                               group, which runs inside on_imu or, with exec.ekf_group_inline
//                               false, in run_ekf_group() on the caller's other thread)
//   on_event(InputEvent)     -> the one dispatch every harness uses: the entry of the event's kind
//                               (fsw/input_event.hpp)
//
// Before navigation starts every input goes to the initialisation (fsw::Initialiser,
// fsw/initialiser.hpp: the initialisation modes, levelling, the static and velocity-matching
// alignments); once it reports an initial state, the application starts the executive with it
// (InitMode::kGiven: the harness gives that state through start_given()). After initialisation
// the raw epochs and the solutions go to the executive, which uses what it gets.
#pragma once

#include <array>
#include <cstdint>

#include "fsw/config_check.hpp"
#include "fsw/executive.hpp"
#include "fsw/flight_app_config.hpp"
#include "fsw/gnss_pvt.hpp"
#include "fsw/gps_orbit.hpp"
#include "fsw/initialiser.hpp"
#include "fsw/input_event.hpp"

namespace fsw {

template <class Layout>
class FlightApp {
 public:
  Status init(const FlightAppConfig& cfg);
  Status on_almanac(const GpsAlmanac& sat);
  Status on_gnss(const GnssRawEpoch& raw);
  /// One GNSS position/velocity solution. kBadInput (counted in pvt_rejected) when invalid.
  Status on_gnss_pvt(const GnssPvtMeasurement& m);
  /// One IMU sample. out.nav_valid is set when the sample completed a minor frame.
  Status on_imu(const ImuSample& s, FrameOutput& out);
  /// One input event (fsw/input_event.hpp), the way every harness feeds the application: calls
  /// the entry of ev.kind. out is written by an IMU event only (the other kinds leave it as it
  /// is): out.nav_valid when the sample completed a minor frame.
  Status on_event(const InputEvent& ev, FrameOutput& out);
  /// InitMode::kGiven: starts navigation from nav (t_s, llh, vel_enu_mps, q_b_n). kBadConfig in any
  /// other mode or before init(), kBadInput for a non-finite state or when already initialised.
  Status start_given(const NavState& nav);
  /// Measured execution time of the previous tick, passed to the executive (real-time mode).
  void set_prev_tick_exec_s(double s) { prev_tick_exec_s_ = s; }
  /// The 1 Hz group (Executive::run_ekf_group): with exec.ekf_group_inline = false the caller runs
  /// it after an out.ekf_released, on its own thread or between two on_imu calls.
  Status run_ekf_group() { return exec_.run_ekf_group(); }
  /// A lockstep caller running the 1 Hz group elsewhere waits for it while this is true.
  bool ekf_result_due_next_frame() const { return health_.initialised && exec_.ekf_result_due_next_frame(); }
  /// Measured execution time of a 1 Hz run (real-time mode).
  void note_ekf_group_exec_s(double s) { exec_.note_ekf_group_exec_s(s); }

  bool initialised() const { return health_.initialised; }
  const Executive<Layout>& executive() const { return exec_; }
  const FlightAppHealth& health() const { return health_; }
  const GpsAlmanacTable& almanac() const { return almanac_; }

 private:
  /// Common end of every initialisation: starts the executive from the initial state, records the
  /// health.
  Status start(const InitialState& initial);

  FlightAppConfig cfg_{};
  bool configured_ = false;
  Executive<Layout> exec_{};
  GpsAlmanacTable almanac_{};
  FlightAppHealth health_{};
  Initialiser initialiser_{};  ///< every input before initialisation
  std::array<ImuSample, FrameBuilder::kMaxSamplesPerFrame> batch_{};
  int n_batch_ = 0;
  GnssEpoch epoch_{};
  bool have_epoch_ = false;
  GnssPvtMeasurement pvt_{};
  bool have_pvt_ = false;
  double prev_tick_exec_s_ = -1.0;
};

#define FSW_FLIGHT_APP_EXTERN(L) extern template class FlightApp<L>;
FSW_FOR_EACH_LAYOUT(FSW_FLIGHT_APP_EXTERN)
#undef FSW_FLIGHT_APP_EXTERN

}  // namespace fsw
