#include "cfg/data_dir.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <mutex>

namespace cfg {
namespace {

std::mutex g_mutex;
std::string g_override;

bool is_dir(const std::string& p) {
  struct stat st{};
  return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}
bool is_file(const std::string& p) {
  struct stat st{};
  return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

/// Absolute, normalised (realpath) form of p, or p itself when it does not resolve.
std::string canonical(const std::string& p) {
  char buf[PATH_MAX];
  if (::realpath(p.c_str(), buf) != nullptr) return buf;
  return p;
}

std::string dirname_of(const std::string& p) {
  const std::size_t slash = p.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return p.substr(0, slash);
}

std::string self_exe() {
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) return "";
  buf[n] = '\0';
  return buf;
}

/// A directory named explicitly (override or environment) must be sdins data.
DataDirLookup named(const std::string& dir, DataDirSource src, const char* how) {
  DataDirLookup r;
  r.source = src;
  if (!is_dir(dir)) {
    r.error = std::string(how) + " names '" + dir + "', which is not a directory";
  } else if (!is_file(dir + "/" + kDataDirMarker)) {
    r.error = std::string(how) + " names '" + dir + "', which is not an sdins data directory (no " + kDataDirMarker +
              " in it; an installed sdins has one in PREFIX/share/sdins, a build tree in build/<preset>/share/sdins)";
  } else {
    r.path = canonical(dir);
  }
  return r;
}

}  // namespace

const char* to_string(DataDirSource s) {
  switch (s) {
    case DataDirSource::kOverride: return "--data-dir";
    case DataDirSource::kEnvironment: return "SDINS_DATA_DIR";
    case DataDirSource::kExecutable: return "beside the executable";
    case DataDirSource::kNotFound: return "not found";
  }
  return "?";
}

void set_data_dir_override(const std::string& dir) {
  const std::lock_guard<std::mutex> lock(g_mutex);
  g_override = dir;
}

DataDirLookup find_data_dir(const std::string& exe_path) {
  std::string over;
  {
    const std::lock_guard<std::mutex> lock(g_mutex);
    over = g_override;
  }
  if (!over.empty()) return named(over, DataDirSource::kOverride, "--data-dir");
  if (const char* env = std::getenv("SDINS_DATA_DIR"); env != nullptr && env[0] != '\0')
    return named(env, DataDirSource::kEnvironment, "SDINS_DATA_DIR");
  const std::string exe = exe_path.empty() ? self_exe() : exe_path;
  DataDirLookup r;
  if (exe.empty()) {
    r.error = "the running executable's path is unknown (/proc/self/exe); set SDINS_DATA_DIR or --data-dir";
    return r;
  }
  const std::string candidate = dirname_of(canonical(exe)) + "/../share/sdins";
  if (is_file(candidate + "/" + kDataDirMarker)) {
    r.path = canonical(candidate);
    r.source = DataDirSource::kExecutable;
    return r;
  }
  r.error = "no sdins data directory beside the executable (looked for " + candidate + "/" + kDataDirMarker +
            "); set SDINS_DATA_DIR or --data-dir to PREFIX/share/sdins";
  return r;
}

std::string data_file(const std::string& relative) {
  const DataDirLookup d = find_data_dir();
  if (!d.ok()) return "<sdins data directory not found: " + d.error + ">/" + relative;
  return d.path + "/" + relative;
}

}  // namespace cfg
