// The one driver of the flight application: every harness (SIL, HIL over CAN, replay of an LCM
// log, the Monte Carlo, the timing audit, the diagnosis, the bare-metal image and its target
// replay) runs fsw::FlightApp through drive(source, driver, observer) below, and nothing else
// constructs a FlightApp (the unit tests of the application itself excepted).
//
//   source    an EventSource: next() hands out the next fsw::InputEvent in delivery order, or
//             nullptr when it has none now (the end of a recording or scenario; a bus input: no
//             decoded event pending). Implemented by sim::SensorStream (the simulated sensors),
//             hal::LcmReplayReader (an LCM log), tools::RecordedSource (a recording in memory),
//             hal::CanFswInput (CAN frames through the receive assembler) and fsw::EventBatch
//             (a fixed array of events, the Monte Carlo's frame and the image's synthetic inputs).
//             next() returns a pointer, not a copy: an InputEvent is 864 B (x86-64) and an
//             in-memory source hands out the event it holds, at no cost per event.
//   driver    the owner of one FlightApp<Layout>: FlightDriver<Layout> (statically sized, no heap,
//             usable in the bare-metal image as a static object), or hal::FswNode, the host node
//             that holds one of a layout chosen at run time and adds the input log, the LCM
//             telemetry, the navigation digest and the 1 Hz thread as its own observers.
//   observer  what watches the application: before(ev) just before the application sees the event,
//             after(ev, status, out) right after; out is the FrameOutput, meaningful for an IMU
//             event (out.nav_valid: the sample completed a minor frame). Timing, truth scoring,
//             telemetry and digests are observers. Static dispatch (a template argument): no virtual
//             call per event in the loop.
//
// The order of the events is the source's; filtering (a GNSS outage, the GNSS input a
// configuration does not take) is a source too: Filtered<Source, Predicate>.
#pragma once

#include <concepts>
#include <cstdint>

#include "fsw/flight_app.hpp"
#include "fsw/input_event.hpp"
#include "fsw/status.hpp"

namespace fsw {

/// A source of input events (see the file header). The event stays valid until the next call.
template <class S>
concept EventSource = requires(S& s) {
  { s.next() } -> std::same_as<const InputEvent*>;
};

/// The observer that watches nothing.
struct NoObserver {
  void before(const InputEvent&) {}
  void after(const InputEvent&, Status, const FrameOutput&) {}
};

/// An observer from a callable f(ev, status, out), called after every event (a harness' inline
/// scoring: the diagnosis, the target replay's records).
template <class F>
struct AfterEach {
  F f;
  void before(const InputEvent&) {}
  void after(const InputEvent& ev, Status st, const FrameOutput& out) { f(ev, st, out); }
};
template <class F>
AfterEach<F> after_each(F f) {
  return AfterEach<F>{f};
}

/// The owner of one flight application (fsw/flight_app.hpp) of the given layout: what a harness
/// holds instead of a FlightApp. step() is the one way an event reaches the application.
template <class Layout>
class FlightDriver {
 public:
  using App = FlightApp<Layout>;

  Status init(const FlightAppConfig& cfg) { return app_.init(cfg); }
  /// InitMode::kGiven (fsw/flight_app.hpp): the harness that knows the truth starts the navigation.
  Status start_given(const NavState& nav) { return app_.start_given(nav); }
  /// One event: observer.before, FlightApp::on_event, observer.after.
  template <class Observer>
  Status step(const InputEvent& ev, Observer& obs) {
    obs.before(ev);
    const Status st = app_.on_event(ev, out_);
    obs.after(ev, st, out_);
    return st;
  }
  /// The output of the last IMU event (out.nav_valid: it completed a minor frame).
  const FrameOutput& frame() const { return out_; }
  /// The application, for its state, health and the calls around the event flow (the 1 Hz group
  /// run elsewhere, the measured execution times).
  App& app() { return app_; }
  const App& app() const { return app_; }

 private:
  App app_{};
  FrameOutput out_{};
};

/// The one driver loop: every event the source has now, in its order, through driver.step(ev, obs).
/// Returns the number of events delivered.
template <EventSource Source, class Driver, class Observer>
std::uint64_t drive(Source& src, Driver& driver, Observer& obs) {
  std::uint64_t n = 0;
  for (const InputEvent* ev = src.next(); ev != nullptr; ev = src.next()) {
    (void)driver.step(*ev, obs);  // a rejected input is counted in the application's health
    ++n;
  }
  return n;
}
template <EventSource Source, class Driver>
std::uint64_t drive(Source& src, Driver& driver) {
  NoObserver none;
  return drive(src, driver, none);
}

/// A source that passes on only the events keep(ev) accepts (an outage, the GNSS input the
/// configuration does not take); the dropped ones are the predicate's to count.
template <EventSource Source, class Keep>
struct Filtered {
  Source& src;
  Keep keep;
  const InputEvent* next() {
    for (const InputEvent* ev = src.next(); ev != nullptr; ev = src.next())
      if (keep(*ev)) return ev;
    return nullptr;
  }
};
template <EventSource Source, class Keep>
Filtered<Source, Keep> filtered(Source& src, Keep keep) {
  return Filtered<Source, Keep>{src, keep};
}

/// A fixed array of events handed out in order (static storage, no heap): the Monte Carlo reads a
/// minor frame's events from the simulator into one and then runs every model over it; the
/// bare-metal image fills one with each step's synthetic inputs.
template <int N>
class EventBatch {
 public:
  static constexpr int kCapacity = N;
  /// Empties the batch (and its handed-out position).
  void clear() { n_ = next_ = 0; }
  /// The slot the next event is written into; false when full.
  InputEvent* slot() { return n_ < N ? &ev_[n_] : nullptr; }
  /// Keeps the event written into slot().
  void commit() { ++n_; }
  /// Hands out the batch again from its first event.
  void rewind() { next_ = 0; }
  int size() const { return n_; }
  bool full() const { return n_ >= N; }
  /// Index of the event handed out last (for what a harness keeps beside the batch, e.g. truth).
  int current() const { return next_ - 1; }
  const InputEvent* next() { return next_ < n_ ? &ev_[next_++] : nullptr; }

 private:
  InputEvent ev_[N];
  int n_ = 0;
  int next_ = 0;
};

}  // namespace fsw
