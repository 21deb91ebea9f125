// The product's run-time data directory: what `sdins` needs besides its own code, shipped in the
// repository and installed with the tool (cmake/SdinsData.cmake lists it, once, for both):
//
//   almanac/   the default YUMA almanac (data/almanac)
//   scenarios/ scenario files (sim/scenarios)
//   config/    filter configurations (config, config/datasets)
//   can/       the CAN protocol as a DBC (hal/can/sdins.dbc)
//   lcm/       the LCM message definitions (hal/lcm/*.lcm)
//   plot/      the plot scripts (tools/plot/*.py)
//   sdins-data.txt  the marker that names a directory as sdins data (and the version)
//
// Where it is found, first match wins (no path of the build machine is compiled in):
//   1. set_data_dir_override(DIR): `sdins --data-dir DIR`;
//   2. the environment variable SDINS_DATA_DIR;
//   3. <directory of the running executable>/../share/sdins: the install layout
//      (PREFIX/bin/sdins -> PREFIX/share/sdins) and the build tree, which mirrors it
//      (build/<preset>/tools/sdins -> build/<preset>/share/sdins, staged by the build).
// A directory named by 1 or 2 must hold the marker; otherwise the lookup fails with a message
// naming the directory and how it was chosen (no silent fall-through to another copy).
#pragma once

#include <string>

namespace cfg {

enum class DataDirSource { kOverride, kEnvironment, kExecutable, kNotFound };
const char* to_string(DataDirSource s);

struct DataDirLookup {
  std::string path;  ///< the data directory (absolute, no trailing '/'); empty when not found
  DataDirSource source = DataDirSource::kNotFound;
  std::string error;  ///< why it was not found (names every place tried)
  bool ok() const { return error.empty(); }
};

/// The name of the marker file inside a data directory.
inline constexpr const char* kDataDirMarker = "sdins-data.txt";

/// `--data-dir DIR` (empty: no override).
void set_data_dir_override(const std::string& dir);

/// Finds the data directory (see the file header). The executable's directory comes from
/// /proc/self/exe; exe_path (tests) replaces it when not empty.
DataDirLookup find_data_dir(const std::string& exe_path = "");

/// DIR/relative for the data directory found; when none is found, the returned path is
/// "<sdins data directory not found: ...>/relative", so that opening it fails with a message that
/// says why.
std::string data_file(const std::string& relative);

}  // namespace cfg
