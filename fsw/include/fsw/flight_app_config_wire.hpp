// The flight configuration as bytes on a wire: every field of fsw::FlightAppConfig in the order of
// FLIGHT_CONFIG_FIELDS (fsw/flight_app_config_fields.hpp), each as 8-byte little-endian words: a
// double as its IEEE-754 bits, an int, bool or InitMode as a two's-complement int64, a uint64 as
// itself, a Vec3 as three doubles. The value, not the object's bytes: the same on every ABI, with
// no padding and no layout to agree on, and each decoded value is checked for its type (a bool is
// 0 or 1, an int fits, an InitMode is one of its values) before the configuration's own rules
// (check_config, FlightApp::init) see it. Used by the target replay's input (fsw/baremetal/replay.hpp),
// written on the host from the one configuration reader (cfg/) and read by the image.
// No heap, no I/O: the caller owns the buffer.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#include "fsw/flight_app_config.hpp"
#include "fsw/flight_app_config_fields.hpp"

namespace fsw {
namespace config_wire {

inline constexpr std::size_t kWord = 8;

constexpr std::size_t words(double) { return 1; }
constexpr std::size_t words(int) { return 1; }
constexpr std::size_t words(bool) { return 1; }
constexpr std::size_t words(std::uint64_t) { return 1; }
constexpr std::size_t words(InitMode) { return 1; }
inline std::size_t words(const Vec3&) { return 3; }

inline void put_word(std::uint8_t*& p, std::uint64_t w) {
  for (int i = 0; i < 8; ++i) *p++ = static_cast<std::uint8_t>(w >> (8 * i));  // little-endian on any host
}
inline std::uint64_t get_word(const std::uint8_t*& p) {
  std::uint64_t w = 0;
  for (int i = 0; i < 8; ++i) w |= static_cast<std::uint64_t>(*p++) << (8 * i);
  return w;
}

inline void put(std::uint8_t*& p, double v) {
  std::uint64_t w;
  std::memcpy(&w, &v, sizeof w);
  put_word(p, w);
}
inline void put(std::uint8_t*& p, std::int64_t v) { put_word(p, static_cast<std::uint64_t>(v)); }
inline void put(std::uint8_t*& p, int v) { put(p, static_cast<std::int64_t>(v)); }
inline void put(std::uint8_t*& p, bool v) { put(p, static_cast<std::int64_t>(v ? 1 : 0)); }
inline void put(std::uint8_t*& p, InitMode v) { put(p, static_cast<std::int64_t>(v)); }
inline void put(std::uint8_t*& p, std::uint64_t v) { put_word(p, v); }
inline void put(std::uint8_t*& p, const Vec3& v) {
  put(p, v.x());
  put(p, v.y());
  put(p, v.z());
}

inline bool get(const std::uint8_t*& p, double& v) {
  const std::uint64_t w = get_word(p);
  std::memcpy(&v, &w, sizeof v);
  return true;
}
inline bool get(const std::uint8_t*& p, std::uint64_t& v) {
  v = get_word(p);
  return true;
}
inline bool get(const std::uint8_t*& p, int& v) {
  const auto w = static_cast<std::int64_t>(get_word(p));
  if (w < std::numeric_limits<int>::min() || w > std::numeric_limits<int>::max()) return false;
  v = static_cast<int>(w);
  return true;
}
inline bool get(const std::uint8_t*& p, bool& v) {
  const std::uint64_t w = get_word(p);
  if (w > 1u) return false;
  v = w == 1u;
  return true;
}
inline bool get(const std::uint8_t*& p, InitMode& v) {
  const std::uint64_t w = get_word(p);
  if (w > static_cast<std::uint64_t>(InitMode::kGiven)) return false;
  v = static_cast<InitMode>(w);
  return true;
}
inline bool get(const std::uint8_t*& p, Vec3& v) {
  double x = 0.0, y = 0.0, z = 0.0;
  get(p, x);
  get(p, y);
  get(p, z);
  v = Vec3(x, y, z);
  return true;
}

}  // namespace config_wire

/// Bytes of the encoded configuration (the same for every value: kWord per scalar).
inline std::size_t flight_config_wire_bytes() {
  static const FlightAppConfig c{};
  std::size_t n = 0;
#define FSW_CONFIG_WIRE_COUNT(path, in_schema) n += config_wire::words(c.path);
  FLIGHT_CONFIG_FIELDS(FSW_CONFIG_WIRE_COUNT)
#undef FSW_CONFIG_WIRE_COUNT
  return n * config_wire::kWord;
}

/// Writes c into out (cap bytes); returns the bytes written, 0 when cap is too small.
inline std::size_t encode_flight_config(const FlightAppConfig& c, std::uint8_t* out, std::size_t cap) {
  if (out == nullptr || cap < flight_config_wire_bytes()) return 0;
  std::uint8_t* p = out;
#define FSW_CONFIG_WIRE_PUT(path, in_schema) config_wire::put(p, c.path);
  FLIGHT_CONFIG_FIELDS(FSW_CONFIG_WIRE_PUT)
#undef FSW_CONFIG_WIRE_PUT
  return static_cast<std::size_t>(p - out);
}

/// Reads exactly flight_config_wire_bytes() bytes into c. kBadInput (c unspecified) for another
/// length or a value its field's type cannot hold; the configuration's rules are the caller's
/// next step (check_config / FlightApp::init).
inline Status decode_flight_config(const std::uint8_t* in, std::size_t n, FlightAppConfig& c) {
  if (in == nullptr || n != flight_config_wire_bytes()) return Status::kBadInput;
  const std::uint8_t* p = in;
  bool ok = true;
#define FSW_CONFIG_WIRE_GET(path, in_schema) ok = config_wire::get(p, c.path) && ok;
  FLIGHT_CONFIG_FIELDS(FSW_CONFIG_WIRE_GET)
#undef FSW_CONFIG_WIRE_GET
  return ok ? Status::kOk : Status::kBadInput;
}

}  // namespace fsw
