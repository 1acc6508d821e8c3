// SPDX-License-Identifier: MIT
// Initial liquid shapes for flow tests: a cell's liquid fraction by sub-sampling.
#pragma once
#include <functional>

#include "core/vec3.hpp"
#include "fluid/fluid_grid.hpp"

namespace tessera::test {

// Liquid fraction of cell (i, j, k) by sub-sampling (m^3 points).
inline double sampled_fraction(const FluidGrid& g, int i, int j, int k, const std::function<bool(const Vec3&)>& inside,
                               int m = 8) {
  int count = 0;
  for (int c = 0; c < m; ++c)
    for (int b = 0; b < m; ++b)
      for (int a = 0; a < m; ++a) {
        const Vec3 p{g.lo().x + (i + (a + 0.5) / m) * g.h(0), g.lo().y + (j + (b + 0.5) / m) * g.h(1),
                     g.lo().z + (k + (c + 0.5) / m) * g.h(2)};
        count += inside(p);
      }
  return double(count) / (m * m * m);
}

}  // namespace tessera::test
