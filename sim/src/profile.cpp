#include "sim/profile.hpp"
#include "cfg/text_file.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <sstream>
#include <string_view>
#include <system_error>
#include <utility>

namespace sim {

using fsw::kDegToRad;
using fsw::kPi;

// ------------------------------------------------------------------------------------------------
// Loader
// ------------------------------------------------------------------------------------------------

namespace {

constexpr std::size_t kFieldCount = 10;
constexpr std::array<const char*, kFieldCount> kFieldNames = {
    "time", "latitude", "longitude", "height", "velocity north", "velocity east", "velocity down",
    "roll", "pitch", "yaw"};

std::string_view trim(std::string_view s) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

/// A short, printable excerpt of a field for error messages.
std::string quote(std::string_view s) {
  constexpr std::size_t kMax = 40;
  std::string out(s.substr(0, kMax));
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) c = '?';
  }
  if (s.size() > kMax) out += "...";
  return "'" + out + "'";
}

/// Parses one data line into row (SI, ENU). Returns an empty string or the reason for rejection.
std::string parse_line(std::string_view line, ProfileRow& row) {
  const std::size_t n_fields = static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
  if (n_fields != kFieldCount) {
    return "expected " + std::to_string(kFieldCount) + " comma-separated fields, found " + std::to_string(n_fields);
  }
  std::array<double, kFieldCount> v{};
  std::size_t start = 0;
  for (std::size_t k = 0; k < kFieldCount; ++k) {
    const std::size_t comma = line.find(',', start);
    const std::string_view field =
        trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    start = comma + 1;  // unused after the last field
    const char* first = field.data();
    const char* last = field.data() + field.size();
    double x = 0.0;
    const std::from_chars_result r = std::from_chars(first, last, x);
    const auto reject = [&](const char* why) {
      return "field " + std::to_string(k + 1) + " (" + kFieldNames[k] + ") " + why + ": " + quote(field);
    };
    if (field.empty() || r.ec == std::errc::invalid_argument || r.ptr != last) return reject("is not a number");
    if (r.ec == std::errc::result_out_of_range) return reject("is out of the range of a double");
    if (!std::isfinite(x)) return reject("is not finite");
    v[k] = x;
  }
  if (std::abs(v[1]) > 90.0) return "latitude " + std::to_string(v[1]) + " deg is outside [-90, 90]";
  if (std::abs(v[8]) > 90.0) return "pitch " + std::to_string(v[8]) + " deg is outside [-90, 90]";
  row.t_s = v[0];
  row.llh = Vec3(v[1] * kDegToRad, v[2] * kDegToRad, v[3]);
  row.vel_enu_mps = Vec3(v[5], v[4], -v[6]);  // NED -> ENU
  row.euler_rad = Vec3(v[7] * kDegToRad, v[8] * kDegToRad, v[9] * kDegToRad);
  return {};
}

}  // namespace

ProfileLoadResult parse_profile_text(const std::string& text, const std::string& source) {
  ProfileLoadResult result;
  const std::string_view all(text);
  std::size_t pos = 0;
  int line_no = 0;
  while (pos < all.size()) {
    const std::size_t nl = all.find('\n', pos);
    const std::string_view line =
        all.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = (nl == std::string_view::npos) ? all.size() : nl + 1;
    ++line_no;
    if (trim(line).empty()) continue;
    ProfileRow row;
    std::string why = parse_line(line, row);
    if (why.empty() && !result.rows.empty() && !(row.t_s > result.rows.back().t_s)) {
      std::ostringstream os;
      os.precision(17);
      os << "time " << row.t_s << " s is not after the previous sample's " << result.rows.back().t_s
         << " s (times must be strictly increasing)";
      why = os.str();
    }
    if (!why.empty()) {
      result.rows.clear();
      result.error = source + ":" + std::to_string(line_no) + ": " + why;
      return result;
    }
    result.rows.push_back(row);
  }
  if (result.rows.empty()) result.error = source + ": no data rows";
  return result;
}

ProfileLoadResult load_profile(const std::string& path) {
  const std::optional<std::string> text = cfg::read_text_file(path);
  if (!text) {
    ProfileLoadResult result;
    result.error = path + ": cannot open file: " + cfg::text_file_problem(path);
    return result;
  }
  return parse_profile_text(*text, path);
}

// ------------------------------------------------------------------------------------------------
// CubicSpline
// ------------------------------------------------------------------------------------------------

CubicSpline::CubicSpline(std::vector<double> x, const std::vector<double>& y) : x_(std::move(x)) {
  const std::size_t n = x_.size();
  if (n == 0 || y.size() != n) {
    x_.assign(1, 0.0);
    a_.assign(1, 0.0);
    b_.assign(1, 0.0);
    c_.assign(1, 0.0);
    d_.assign(1, 0.0);
    return;
  }
  if (n == 1) {
    a_ = {y[0]};
    b_ = {0.0};
    c_ = {0.0};
    d_ = {0.0};
    return;
  }
  std::vector<double> h(n - 1), delta(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    h[i] = x_[i + 1] - x_[i];
    delta[i] = (y[i + 1] - y[i]) / h[i];
  }
  // Second derivatives M_i at the knots.
  std::vector<double> M(n, 0.0);
  if (n == 3) {
    // Not-a-knot with three points: the interpolating parabola.
    const double m = 2.0 * (delta[1] - delta[0]) / (h[0] + h[1]);
    std::fill(M.begin(), M.end(), m);
  } else if (n >= 4) {
    // Continuity of the second derivative at the interior knots i = 1 .. n-2:
    //   h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1} = 6 (delta_i - delta_{i-1}).
    // Not-a-knot (continuous third derivative at x_1 and x_{n-2}) gives
    //   M_0 = (1 + h_0/h_1) M_1 - (h_0/h_1) M_2,  M_{n-1} = (1 + r) M_{n-2} - r M_{n-3}, r = h_{n-2}/h_{n-3},
    // which, substituted into the first and last equations, leaves a diagonally dominant
    // tridiagonal system in M_1 .. M_{n-2} (solved by the Thomas algorithm).
    const std::size_t m = n - 2;
    std::vector<double> lo(m, 0.0), di(m, 0.0), up(m, 0.0), rhs(m, 0.0);
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t i = k + 1;
      lo[k] = h[i - 1];
      di[k] = 2.0 * (h[i - 1] + h[i]);
      up[k] = h[i];
      rhs[k] = 6.0 * (delta[i] - delta[i - 1]);
    }
    const double h0 = h[0], h1 = h[1];
    di[0] = 3.0 * h0 + 2.0 * h1 + h0 * h0 / h1;
    up[0] = h1 - h0 * h0 / h1;
    lo[0] = 0.0;
    const double ha = h[n - 3], hb = h[n - 2];
    lo[m - 1] = ha - hb * hb / ha;
    di[m - 1] = 2.0 * ha + 3.0 * hb + hb * hb / ha;
    up[m - 1] = 0.0;
    for (std::size_t k = 1; k < m; ++k) {
      const double w = lo[k] / di[k - 1];
      di[k] -= w * up[k - 1];
      rhs[k] -= w * rhs[k - 1];
    }
    M[m] = rhs[m - 1] / di[m - 1];
    for (std::size_t k = m - 1; k-- > 0;) M[k + 1] = (rhs[k] - up[k] * M[k + 2]) / di[k];
    M[0] = (1.0 + h0 / h1) * M[1] - (h0 / h1) * M[2];
    M[n - 1] = (1.0 + hb / ha) * M[n - 2] - (hb / ha) * M[n - 3];
  }
  a_.resize(n - 1);
  b_.resize(n - 1);
  c_.resize(n - 1);
  d_.resize(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    a_[i] = y[i];
    b_[i] = delta[i] - h[i] * (2.0 * M[i] + M[i + 1]) / 6.0;
    c_[i] = 0.5 * M[i];
    d_[i] = (M[i + 1] - M[i]) / (6.0 * h[i]);
  }
}

std::size_t CubicSpline::interval(double x) const {
  if (a_.size() <= 1) return 0;
  const auto it = std::upper_bound(x_.begin(), x_.end(), x);
  const std::ptrdiff_t i = std::distance(x_.begin(), it) - 1;
  return static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(i, 0, static_cast<std::ptrdiff_t>(a_.size()) - 1));
}

double CubicSpline::value(double x) const {
  const std::size_t i = interval(x);
  const double u = x - x_[i];
  return a_[i] + u * (b_[i] + u * (c_[i] + u * d_[i]));
}

double CubicSpline::derivative(double x) const {
  const std::size_t i = interval(x);
  const double u = x - x_[i];
  return b_[i] + u * (2.0 * c_[i] + 3.0 * u * d_[i]);
}

double CubicSpline::second_derivative(double x) const {
  const std::size_t i = interval(x);
  const double u = x - x_[i];
  return 2.0 * c_[i] + 6.0 * u * d_[i];
}

// ------------------------------------------------------------------------------------------------
// ProfileMotion
// ------------------------------------------------------------------------------------------------

std::unique_ptr<ProfileMotion> ProfileMotion::create(std::vector<ProfileRow> rows, std::string& error) {
  if (rows.size() < 4) {
    error = "a profile needs at least 4 samples for the cubic splines, got " + std::to_string(rows.size());
    return nullptr;
  }
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const ProfileRow& r = rows[i];
    const bool finite = std::isfinite(r.t_s) && r.llh.allFinite() && r.vel_enu_mps.allFinite() &&
                        r.euler_rad.allFinite();
    if (!finite) {
      error = "sample " + std::to_string(i) + " is not finite";
      return nullptr;
    }
    if (i > 0 && !(r.t_s > rows[i - 1].t_s)) {
      error = "sample " + std::to_string(i) + ": times must be strictly increasing";
      return nullptr;
    }
    if (std::abs(r.euler_rad.y()) > kMaxAbsPitchDeg * kDegToRad) {
      error = "sample " + std::to_string(i) + ": |pitch| exceeds " + std::to_string(kMaxAbsPitchDeg) +
              " deg (Euler-angle interpolation is singular near +/-90 deg)";
      return nullptr;
    }
  }

  std::unique_ptr<ProfileMotion> m(new ProfileMotion());
  const std::size_t n = rows.size();
  std::vector<double> t(n);
  std::array<std::vector<double>, 3> vel, euler;
  for (auto& c : vel) c.resize(n);
  for (auto& c : euler) c.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    t[i] = rows[i].t_s;
    for (int k = 0; k < 3; ++k) {
      vel[static_cast<std::size_t>(k)][i] = rows[i].vel_enu_mps(k);
      euler[static_cast<std::size_t>(k)][i] = rows[i].euler_rad(k);
    }
  }
  // Unwrap the heading (and, for completeness, roll): successive samples are taken to differ by
  // less than half a turn, so a jump across +/-180 deg or 0/360 deg is a wrap, not a motion.
  for (std::size_t k : {std::size_t{0}, std::size_t{2}}) {
    std::vector<double>& a = euler[k];
    for (std::size_t i = 1; i < n; ++i) {
      const double step = std::remainder(a[i] - a[i - 1], 2.0 * kPi);  // in [-pi, pi]
      a[i] = a[i - 1] + step;
    }
  }
  for (std::size_t k = 0; k < 3; ++k) {
    m->vel_[k] = CubicSpline(t, vel[k]);
    m->euler_[k] = CubicSpline(t, euler[k]);
  }
  m->rows_ = std::move(rows);
  return m;
}

Motion::State ProfileMotion::initial_state() const {
  State y = State::Zero();
  y.head<3>() = rows_.front().llh;
  return y;
}

Vec3 ProfileMotion::velocity_enu(double t_s) const {
  const double tp = start_time_s() + t_s;
  return Vec3(vel_[0].value(tp), vel_[1].value(tp), vel_[2].value(tp));
}

Vec3 ProfileMotion::acceleration_enu(double t_s) const {
  const double tp = start_time_s() + t_s;
  return Vec3(vel_[0].derivative(tp), vel_[1].derivative(tp), vel_[2].derivative(tp));
}

Mat3 ProfileMotion::C_b_n(double t_s) const {
  const double tp = start_time_s() + t_s;
  return fsw::C_b_n_from_euler(euler_[0].value(tp), euler_[1].value(tp), euler_[2].value(tp));
}

Motion::State ProfileMotion::derivative(double t_s, const State& y) const {
  const Vec3 rate = fsw::llh_rate(y.head<3>(), velocity_enu(t_s));
  State d = State::Zero();
  d.head<3>() = rate;
  return d;
}

Kinematics ProfileMotion::eval(double t_s, const State& y) const {
  const double tp = start_time_s() + t_s;
  const double roll = euler_[0].value(tp), pitch = euler_[1].value(tp), heading = euler_[2].value(tp);
  Kinematics k;
  k.llh = y.head<3>();
  k.vel_enu_mps = velocity_enu(t_s);
  k.acc_enu_mps2 = acceleration_enu(t_s);
  k.C_b_n = fsw::C_b_n_from_euler(roll, pitch, heading);
  k.omega_nb_b_radps = fsw::omega_nb_b_from_euler_rates(roll, pitch, euler_[0].derivative(tp),
                                                        euler_[1].derivative(tp), euler_[2].derivative(tp));
  return k;
}

}  // namespace sim
