// The navigation digest: FNV-1a over every navigation frame's t_s, llh, vel_enu_mps and q_b_n
// bytes, the one fingerprint by which SIL, HIL, replay and the Cortex-M7 replay are compared
// (bit-identical runs give equal digests). fsw rules: no heap, no I/O.
#pragma once

#include <cstddef>
#include <cstdint>

#include "fsw/strapdown.hpp"

namespace fsw {

inline constexpr std::uint64_t kNavDigestSeed = 1469598103934665603ull;  ///< FNV-1a 64-bit offset basis

/// Folds n bytes at p into the FNV-1a hash h.
inline void fnv1a(std::uint64_t& h, const void* p, std::size_t n) {
  constexpr std::uint64_t kPrime = 1099511628211ull;
  const auto* b = static_cast<const unsigned char*>(p);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= b[i];
    h *= kPrime;
  }
}

/// Folds one navigation frame into the digest h.
inline void nav_digest_add(std::uint64_t& h, const NavState& n) {
  fnv1a(h, &n.t_s, sizeof n.t_s);
  fnv1a(h, n.llh.data(), 3 * sizeof(double));
  fnv1a(h, n.vel_enu_mps.data(), 3 * sizeof(double));
  fnv1a(h, n.q_b_n.coeffs().data(), 4 * sizeof(double));
}

}  // namespace fsw
