// The flight application's one input type: every harness (SIL, HIL over CAN, replay of an LCM
// log, the Monte Carlo and the paper run, the timing audit, the diagnosis, the target replay)
// hands the flight software its inputs as fsw::InputEvent through the one driver loop
// (fsw/driver.hpp: fsw::drive), whose driver calls FlightApp::on_event, the one dispatch
// (flight_app.hpp). The event sources hand them out: the simulated sensor stream, the LCM log
// reader, the recording in memory, the CAN input (the receive assembler's outputs).
//
// Statically sized (one slot per payload, no union: the payloads hold Eigen values), no heap.
// Only the payload named by `kind` is meaningful. A harness that holds a whole recording in
// memory keeps it in typed arrays (tools::RecordedData) and fills one InputEvent per delivery:
// an InputEvent is 864 B on x86-64, too large to store a 1 kHz recording as a vector of them.
#pragma once

#include <cstdint>

#include "fsw/gnss.hpp"
#include "fsw/gps_orbit.hpp"
#include "fsw/strapdown.hpp"

namespace fsw {

struct InputEvent {
  enum class Kind : std::uint8_t {
    kImu,      ///< imu (+ imu_counter, imu_status)
    kGnssRaw,  ///< gnss: a raw receiver epoch (pseudoranges, rates)
    kGnssPvt,  ///< pvt: a receiver's position/velocity solution
    kAlmanac,  ///< almanac: one satellite's almanac element
  };
  Kind kind = Kind::kImu;
  double t_s = 0.0;  ///< arrival time on the navigation time scale (almanac: when received) [s]

  ImuSample imu{};
  std::int32_t imu_counter = -1;  ///< the sensor's sample counter; -1: none (a simulated sample)
  std::int16_t imu_status = 0;    ///< sensor status bits (sdins::imu_sample_t::STATUS_*)
  GnssRawEpoch gnss{};
  GnssPvtMeasurement pvt{};
  GpsAlmanac almanac{};

  static InputEvent of_imu(const ImuSample& s, std::int32_t counter = -1, std::int16_t status = 0) {
    InputEvent e = of_kind(Kind::kImu, s.t_s);
    e.imu = s;
    e.imu_counter = counter;
    e.imu_status = status;
    return e;
  }
  static InputEvent of_gnss(const GnssRawEpoch& g) {
    InputEvent e = of_kind(Kind::kGnssRaw, g.t_s);
    e.gnss = g;
    return e;
  }
  static InputEvent of_pvt(const GnssPvtMeasurement& m) {
    InputEvent e = of_kind(Kind::kGnssPvt, m.t_s);
    e.pvt = m;
    return e;
  }
  static InputEvent of_almanac(const GpsAlmanac& a, double t_s) {
    InputEvent e = of_kind(Kind::kAlmanac, t_s);
    e.almanac = a;
    return e;
  }

 private:
  static InputEvent of_kind(Kind k, double t_s) {
    InputEvent e;
    e.kind = k;
    e.t_s = t_s;
    return e;
  }
};

inline const char* to_string(InputEvent::Kind k) {
  switch (k) {
    case InputEvent::Kind::kImu: return "imu";
    case InputEvent::Kind::kGnssRaw: return "gnss_raw";
    case InputEvent::Kind::kGnssPvt: return "gnss_pvt";
    case InputEvent::Kind::kAlmanac: return "almanac";
  }
  return "?";
}

}  // namespace fsw
