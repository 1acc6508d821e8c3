// SPDX-License-Identifier: MIT
// The Morton (Z-order) code of a point in a box: 21 bits per direction, interleaved. Sorting by it
// puts neighbours in space close in memory (the DEM's body keys, the blast's element order).
#pragma once
#include <algorithm>
#include <cstdint>

#include "core/vec3.hpp"

namespace tessera {

// Interleaves the low 21 bits of x, y, z.
inline std::uint64_t morton(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  auto spread = [](std::uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}

// The code of p in the box [lo, hi] (points outside are clamped to it).
inline std::uint64_t morton(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  std::uint64_t q[3];
  for (int d = 0; d < 3; ++d) {
    const double t = hi[d] > lo[d] ? (p[d] - lo[d]) / (hi[d] - lo[d]) : 0.0;
    q[d] = static_cast<std::uint64_t>(std::clamp(t, 0.0, 1.0) * 2097151.0);
  }
  return morton(q[0], q[1], q[2]);
}

}  // namespace tessera
