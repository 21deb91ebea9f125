// Heights above mean sea level (EGM96) to ellipsoidal heights through PROJ (Debian libproj-dev,
// the geoid grid from proj-data): EPSG:4326+5773 (WGS 84 + EGM96 height) -> EPSG:4979 (WGS 84 3D).
// Debian 12's proj-data ships the grid as egm96_15.gtx; PROJ finds it for the EPSG transformation
// through proj.db's grid alternatives (the newer name is us_nga_egm96_15.tif).
#include <proj.h>

#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>

#include "fsw/frames.hpp"
#include "tools/import_describe.hpp"

namespace tools {
namespace {

struct Egm96 {
  PJ_CONTEXT* ctx = nullptr;
  PJ* pj = nullptr;
  std::string error;
  Egm96() {
    ctx = proj_context_create();
    PJ* raw = proj_create_crs_to_crs(ctx, "EPSG:4326+5773", "EPSG:4979", nullptr);
    if (raw == nullptr) {
      error = proj_context_errno_string(ctx, proj_context_errno(ctx));
      return;
    }
    pj = proj_normalize_for_visualization(ctx, raw);  // lon, lat order in degrees
    proj_destroy(raw);
    if (pj == nullptr) error = proj_context_errno_string(ctx, proj_context_errno(ctx));
  }
  ~Egm96() {
    if (pj != nullptr) proj_destroy(pj);
    proj_context_destroy(ctx);
  }
};

}  // namespace

double egm96_msl_to_ellipsoid_m(double lat_rad, double lon_rad, double msl_m) {
  static Egm96 g;
  static std::mutex m;
  const std::lock_guard<std::mutex> lock(m);
  if (g.pj == nullptr)
    throw std::runtime_error("PROJ cannot convert EGM96 heights (" + g.error +
                             "; Debian: libproj-dev and proj-data with the EGM96 grid, tools/setup)");
  PJ_COORD c = proj_coord(lon_rad * fsw::kRadToDeg, lat_rad * fsw::kRadToDeg, msl_m, 0.0);
  proj_errno_reset(g.pj);
  const PJ_COORD out = proj_trans(g.pj, PJ_FWD, c);
  if (proj_errno(g.pj) != 0 || !std::isfinite(out.xyz.z) || std::abs(out.xyz.z - msl_m) > 200.0)
    throw std::runtime_error("PROJ could not convert an EGM96 height (the geoid grid egm96_15.gtx / us_nga_egm96_15.tif "
                             "of Debian's proj-data missing?): " +
                             std::string(proj_errno_string(proj_errno(g.pj))));
  return out.xyz.z;
}

}  // namespace tools
