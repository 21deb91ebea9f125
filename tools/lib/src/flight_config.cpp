#include "tools/flight_config.hpp"

#include <stdexcept>

namespace tools {

const sim::FilterConfig& shipped_filter_config() {
  // A failed read throws out of the initialiser, so the next call tries again.
  static const sim::FilterConfig shipped = [] { return filter_config(""); }();
  return shipped;
}

sim::FilterConfig filter_config(const std::string& path) {
  sim::FilterConfig f;
  const sim::FilterConfigParseResult r = sim::load_filter_config(path, f);
  if (!r.ok) throw std::runtime_error(r.error);
  return f;
}

void require_raw_gnss(const sim::FilterConfig& f, const std::string& what, const std::string& why) {
  if (f.gnss_source != sim::GnssSource::kRaw)
    throw std::runtime_error(what + ": gnss.source = \"" + std::string(sim::to_string(f.gnss_source)) + "\", but " +
                             why + "; use \"raw\"");
}

}  // namespace tools
