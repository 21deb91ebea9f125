// The flight software's fields as the files name them: each field of fsw/config_check.hpp that a
// file sets, its TOML key, and the one conversion between the file's unit and the flight
// software's SI unit. The reader converts with it (flight_config.cpp), a refusal quotes a value
// back in the file's unit with it (validate.cpp). Private to cfg.
#pragma once

#include "fsw/config_check.hpp"

namespace cfg::keys {

/// A flight-software field's TOML key and the one conversion between the file's unit and the
/// flight software's SI unit: the reader converts with to_si, a refusal quotes the value back in
/// the file's unit with from_si. alt_key: the same value in another unit (imu.*_per_rthr).
struct Key {
  fsw::ConfigField field;
  const char* key;
  double (*to_si)(double) = nullptr;  ///< nullptr: the file's unit is the SI unit
  double (*from_si)(double) = nullptr;
  const char* alt_key = nullptr;
  double (*alt_to_si)(double) = nullptr;
  double (*alt_from_si)(double) = nullptr;
};

/// The key of a field; nullptr when no file key sets it.
const Key* find_key(fsw::ConfigField field);
/// A file value in the flight software's unit.
double to_si(fsw::ConfigField field, double v);
/// The same for a value given with the key's other unit (Key::alt_key).
double alt_to_si(fsw::ConfigField field, double v);

}  // namespace cfg::keys
