// Where the tests find the measured recordings (optional; docs/data.md): the environment variable
// SDINS_RECORDINGS_DIR, else this source tree's default, ../shared/data beside it. Tests that need
// a recording skip with the reason when it is absent.
#pragma once

#include <cstdlib>
#include <string>

namespace test {

inline std::string recordings_dir() {
  const char* e = std::getenv("SDINS_RECORDINGS_DIR");
  return e != nullptr && e[0] != '\0' ? std::string(e) : std::string(SDINS_DEFAULT_RECORDINGS_DIR);
}

}  // namespace test
