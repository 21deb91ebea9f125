// Task entry points for the stack audit (sdins audit stack; docs/audits.md). Compiled only in
// the stack-audit build (-DSDINS_STACK_AUDIT=ON, cmake/StackAudit.cmake), never linked into a
// program.
//
// Each wrapper forwards one call. The audit finds a wrapper in the call graph by its unmangled
// extern "C" name and takes its single callee as the real function, so the task table in
// tools/sdins/cmd_audit.cpp names layouts (Layout24) instead of spelling out mangled template
// names. The wrappers' own frames are not counted: every task is rooted at the callee.
#include "fsw/ekf.hpp"
#include "fsw/executive.hpp"
#include "fsw/flight_app.hpp"
#include "fsw/strapdown.hpp"

#define SDINS_STACK_ENTRIES(L)                                                                                    \
  extern "C" fsw::Status sdins_stack_entry_tick_##L(fsw::Executive<fsw::L>& e, const fsw::FrameInput& in,        \
                                                    fsw::FrameOutput& out) {                                     \
    return e.tick(in, out);                                                                                       \
  }                                                                                                               \
  extern "C" fsw::Status sdins_stack_entry_ekf_group_##L(fsw::Executive<fsw::L>& e) { return e.run_ekf_group(); }  \
  extern "C" fsw::Status sdins_stack_entry_accumulate_##L(fsw::Ekf<fsw::L>& k, const fsw::FrameIncrement& inc,   \
                                                          const fsw::NavState& nav) {                            \
    return k.accumulate(inc, nav);                                                                                \
  }                                                                                                               \
  extern "C" fsw::Status sdins_stack_entry_propagate_##L(fsw::Ekf<fsw::L>& k) { return k.propagate(); }          \
  extern "C" fsw::Status sdins_stack_entry_update_##L(fsw::Ekf<fsw::L>& k, const fsw::GnssEpoch& epoch,          \
                                                      const fsw::NavState& nav, const fsw::Vec3& w,              \
                                                      fsw::EkfUpdateReport& rep) {                               \
    return k.update(epoch, nav, w, rep);                                                                          \
  }                                                                                                               \
  extern "C" fsw::Status sdins_stack_entry_update_pvt_##L(fsw::Ekf<fsw::L>& k, const fsw::GnssPvtMeasurement& m, \
                                                          const fsw::NavState& nav, const fsw::Vec3& w,          \
                                                          fsw::EkfUpdateReport& rep) {                           \
    return k.update_pvt(m, nav, w, rep);                                                                          \
  }                                                                                                               \
  extern "C" fsw::Status sdins_stack_entry_feedback_##L(fsw::Ekf<fsw::L>& k, fsw::Strapdown& ins,                \
                                                        fsw::ImuCompensation& comp) {                            \
    return k.feedback(ins, comp);                                                                                 \
  }

SDINS_STACK_ENTRIES(Layout15)
SDINS_STACK_ENTRIES(Layout24)
SDINS_STACK_ENTRIES(Layout15Full)
SDINS_STACK_ENTRIES(Layout24Full)

// The flight application's entries, as HIL, SIL, replay, the Monte Carlo and the bare-metal image
// call them: the IMU sample (levelling and alignment before initialisation; after it the batching
// and, on a frame's last sample, Executive::tick with the 200 Hz group and, when due, the 1 Hz
// group), the raw GNSS epoch (satellite positions from the almanac; before initialisation the
// single-point solution and the initialisation it may complete), the solution input (validation,
// initialisation from a solution), and the one dispatch every harness calls, on_event.
#define SDINS_STACK_APP_ENTRIES(L)                                                                                \
  extern "C" fsw::Status sdins_stack_entry_on_event_##L(fsw::FlightApp<fsw::L>& a, const fsw::InputEvent& ev,      \
                                                        fsw::FrameOutput& out) {                                   \
    return a.on_event(ev, out);                                                                                   \
  }                                                                                                               \
  extern "C" fsw::Status sdins_stack_entry_on_imu_##L(fsw::FlightApp<fsw::L>& a, const fsw::ImuSample& s,          \
                                                      fsw::FrameOutput& out) {                                     \
    return a.on_imu(s, out);                                                                                      \
  }                                                                                                               \
  extern "C" fsw::Status sdins_stack_entry_on_gnss_##L(fsw::FlightApp<fsw::L>& a, const fsw::GnssRawEpoch& e) {   \
    return a.on_gnss(e);                                                                                          \
  }                                                                                                               \
  extern "C" fsw::Status sdins_stack_entry_on_gnss_pvt_##L(fsw::FlightApp<fsw::L>& a,                             \
                                                           const fsw::GnssPvtMeasurement& m) {                    \
    return a.on_gnss_pvt(m);                                                                                      \
  }

SDINS_STACK_APP_ENTRIES(Layout15Full)
SDINS_STACK_APP_ENTRIES(Layout24Full)

extern "C" fsw::Status sdins_stack_entry_strapdown_step(fsw::Strapdown& s, const fsw::FrameIncrement& inc) {
  return s.step(inc);
}
extern "C" fsw::Status sdins_stack_entry_frame_builder_add(fsw::FrameBuilder& b, const fsw::ImuSample& s) {
  return b.add(s);
}
