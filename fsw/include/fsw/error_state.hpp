// The one error-state layout type: the EKF of every model (the paper's 15-state and 24-state
// filters, and the extended models of the diagnosis) is the same code instantiated with a layout,
// and the tools read estimates and covariances through the same layout.
//
// A layout is an ordered list of blocks. Every block has a compile-time size; the layout gives
// each block its offset and the total size, so matrices are fixed-size Eigen types (no heap).
//
// ERROR DEFINITIONS (estimate minus truth unless stated; frames as in frames.hpp)
//   kPosition       delta p   ENU metres of the navigation solution (IMU reference point)
//   kVelocity       delta v   ENU m/s
//   kAttitude       phi       attitude error, C_b_n_hat = (I - [phi x]) C_b_n (phi_E, phi_N, phi_U) rad
//   kAccelBias      residual accelerometer bias (true minus compensated) m/s^2, body axes
//   kGyroBias       residual gyro bias rad/s, body axes
//   kAccelMisalign  residual accelerometer misalignment yx, zx, zy rad (effect_catalogue.hpp)
//   kGyroMisalign   residual gyro misalignment xy, xz, yx, yz, zx, zy rad
//   kAccelScale     residual accelerometer scale factor x, y, z (dimensionless)
//   kGyroScale      residual gyro scale factor x, y, z (dimensionless)
//   kClock          receiver clock bias [m] and drift [m/s], estimate minus truth
//   kRangeError     first-order Gauss-Markov pseudorange error of each receiver channel [m]
//   kRangeRateError first-order Gauss-Markov pseudorange-rate error of each channel [m/s]
//                   (estimate minus truth; a channel is bound to a PRN while it is tracked)
//   kGyroGSens      residual gyro g-sensitivity, gyro i senses G_i f_i (true minus compensated)
//                   rad/s per m/s^2, body axes
//   kTimeOffset     IMU-GNSS time offset (IMU time tag minus GNSS time) s, estimate minus truth
//   kLeverArm       IMU reference point -> antenna, body axes m, estimate minus truth
//   kTropoScale     scale of the tropospheric delay model (saastamoinen_delay_m), estimate minus truth
//   kIonoScale      scale of the ionospheric delay model (klobuchar_delay_m), estimate minus truth
//   kTimeDrift      rate of the IMU-GNSS time offset (the IMU clock's rate error against GNSS
//                   time) s/s, estimate minus truth: offset(t) = offset + drift (t - t_ref), t_ref
//                   the GNSS time of the first measurement update
// The residual sensor errors are what remains after the IMU compensation that the filter feeds
// back: measured = (I + SF + M) true + b, compensated = measured - b_hat - (SF_hat + M_hat) measured,
// so compensated ~ true + delta b + (delta SF + delta M) true.
//
// THE TWO STANDARD MODELS
//   Layout15: the paper's 15 states (position, velocity, attitude, accel bias, gyro bias) plus the
//             two receiver clock states that tight coupling needs: 17 states.
//   Layout24: the paper's 24 states (the 15 plus 3 accelerometer and 6 gyro misalignments) plus
//             the two clock states: 26 states.
//   Layout15Full, Layout24Full: the same two models for the simulator's full error set. Both
//             estimate exactly the paper's states (15 or 24) plus the clock, and add
//             - one first-order Gauss-Markov error state per receiver channel for pseudorange and
//               for pseudorange rate (2 x 12): the simulated GPS errors are correlated in time;
//             - consider (Schmidt) states for what the model does not estimate: accelerometer and
//               gyro scale factors for both, and the 9 misalignments for the 15-state model. They
//               keep each filter's covariance honest (and its NEES meaningful) without changing
//               what it estimates.
//             56 states each.
#pragma once

#include <cstddef>
#include <cstdint>

namespace fsw {

enum class Block : std::uint8_t {
  kPosition = 0,
  kVelocity,
  kAttitude,
  kAccelBias,
  kGyroBias,
  kAccelMisalign,
  kGyroMisalign,
  kAccelScale,
  kGyroScale,
  kClock,
  kRangeError,
  kRangeRateError,
  kGyroGSens,
  kTimeOffset,
  kLeverArm,
  kTropoScale,
  kIonoScale,
  kTimeDrift,
  kCount
};

/// Receiver channels whose time-correlated measurement errors a layout can carry as states.
inline constexpr int kGnssErrorChannels = 12;

inline constexpr int kBlockCount = static_cast<int>(Block::kCount);

/// Size of each block, indexed by Block.
inline constexpr int kBlockSize[kBlockCount] = {3, 3, 3, 3, 3, 3, 6, 3, 3, 2, kGnssErrorChannels, kGnssErrorChannels,
                                                3, 1, 3, 1, 1, 1};

/// Short block names for reports and CSV headers.
inline constexpr const char* kBlockName[kBlockCount] = {"pos",       "vel",       "att",       "accel_bias",
                                                         "gyro_bias", "accel_mis", "gyro_mis",  "accel_sf",
                                                         "gyro_sf",   "clock",     "range_err", "range_rate_err",
                                                         "gyro_g_sens", "time_offset", "lever_arm", "tropo_scale",
                                                         "iono_scale", "time_drift"};

constexpr int block_size(Block b) { return kBlockSize[static_cast<int>(b)]; }

template <Block... Blocks>
struct ErrorStateLayout {
  static constexpr int kSize = (block_size(Blocks) + ...);
  static constexpr int kNumBlocks = static_cast<int>(sizeof...(Blocks));
  static constexpr Block kBlocks[kNumBlocks] = {Blocks...};

  static constexpr bool has(Block b) {
    for (Block x : kBlocks)
      if (x == b) return true;
    return false;
  }
  /// Consider (Schmidt) blocks are carried in the covariance but never estimated (zero gain).
  static constexpr bool is_consider(Block) { return false; }
  /// Offset of block b in the state vector, or -1 when the layout does not have it.
  static constexpr int offset(Block b) {
    int off = 0;
    for (Block x : kBlocks) {
      if (x == b) return off;
      off += block_size(x);
    }
    return -1;
  }
};

/// A layout whose listed blocks are consider states (Schmidt-Kalman): their uncertainty and its
/// effect on the others are propagated and kept in P, but the filter does not estimate them. A
/// model thus stays consistent with error sources it does not estimate.
template <class Base, Block... Considered>
struct ConsiderLayout : Base {
  static constexpr bool is_consider(Block b) { return ((b == Considered) || ...); }
};

/// The three navigation blocks must lead every layout, in this order: the EKF propagates the
/// navigation error block (first 9 states) densely and every other block as a random constant or
/// random walk.
template <class Layout>
constexpr bool kNavigationBlocksLead = Layout::offset(Block::kPosition) == 0 && Layout::offset(Block::kVelocity) == 3 &&
                                       Layout::offset(Block::kAttitude) == 6;

using Layout15 = ErrorStateLayout<Block::kPosition, Block::kVelocity, Block::kAttitude, Block::kAccelBias,
                                  Block::kGyroBias, Block::kClock>;
using Layout24 = ErrorStateLayout<Block::kPosition, Block::kVelocity, Block::kAttitude, Block::kAccelBias,
                                  Block::kGyroBias, Block::kAccelMisalign, Block::kGyroMisalign, Block::kClock>;

/// The layout that carries every error source of the simulator's paper error set.
using LayoutFull = ErrorStateLayout<Block::kPosition, Block::kVelocity, Block::kAttitude, Block::kAccelBias,
                                    Block::kGyroBias, Block::kAccelMisalign, Block::kGyroMisalign, Block::kAccelScale,
                                    Block::kGyroScale, Block::kClock, Block::kRangeError, Block::kRangeRateError>;
using Layout15Full = ConsiderLayout<LayoutFull, Block::kAccelMisalign, Block::kGyroMisalign, Block::kAccelScale,
                                    Block::kGyroScale>;
using Layout24Full = ConsiderLayout<LayoutFull, Block::kAccelScale, Block::kGyroScale>;
/// The conventional 15-state filter of the paper for the full error set: the misalignments are
/// neither estimated nor considered (the filter does not know they exist); scale factors are
/// considered and the GPS errors modelled exactly as in Layout24Full, so the two differ only in
/// the misalignments. 50 states.
using Layout15Conv =
    ConsiderLayout<ErrorStateLayout<Block::kPosition, Block::kVelocity, Block::kAttitude, Block::kAccelBias,
                                    Block::kGyroBias, Block::kAccelScale, Block::kGyroScale, Block::kClock,
                                    Block::kRangeError, Block::kRangeRateError>,
                   Block::kAccelScale, Block::kGyroScale>;

/// The diagnosis model (tools/diagnosis): the 15-state model with the clock and the per-channel
/// Gauss-Markov GPS errors, plus one block for every error of the effect catalogue
/// (effect_catalogue.hpp). The diagnosis switches blocks on and off at run time through their
/// initial sigma (EkfConfig): a block started with zero variance and no process noise stays
/// exactly zero and uncorrelated, so the model with every extension off is the baseline. 66 states.
using LayoutDiag =
    ErrorStateLayout<Block::kPosition, Block::kVelocity, Block::kAttitude, Block::kAccelBias, Block::kGyroBias,
                     Block::kAccelMisalign, Block::kGyroMisalign, Block::kAccelScale, Block::kGyroScale,
                     Block::kGyroGSens, Block::kTimeOffset, Block::kTimeDrift, Block::kLeverArm, Block::kTropoScale,
                     Block::kIonoScale, Block::kClock, Block::kRangeError, Block::kRangeRateError>;

/// The layouts the flight software is built for, named once: every explicit instantiation of a
/// layout template in fsw/ (Ekf and its aid units, EkfTransition, the executive's rate groups and
/// scheduler, FlightApp) and its extern declaration expand this list, so adding a layout is one entry
/// here.
#define FSW_FOR_EACH_LAYOUT(X) X(Layout15) X(Layout24) X(Layout15Full) X(Layout24Full) X(Layout15Conv) X(LayoutDiag)

static_assert(Layout15::kSize == 17, "15-state model plus two clock states");
static_assert(LayoutDiag::kSize == 66);
static_assert(Layout24::kSize == 26, "24-state model plus two clock states");
static_assert(LayoutFull::kSize == 56);
static_assert(Layout15Full::is_consider(Block::kGyroMisalign) && !Layout24Full::is_consider(Block::kGyroMisalign));
static_assert(kNavigationBlocksLead<Layout15> && kNavigationBlocksLead<Layout24>);

}  // namespace fsw
