// SPDX-License-Identifier: MIT
// PLIC geometry in one cell (src/fluid/plic.hpp): closed-form volumes against hand values and
// point counting, the inverse against the forward map, and the flux slab.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fluid/plic.hpp"

using namespace tessera::plic;

TEST(Plic, HandValues) {
  EXPECT_NEAR(plane_volume(1, 0, 0, 0.3), 0.3, 1e-15);
  EXPECT_NEAR(plane_volume(0, -2, 0, -0.6), 0.7, 1e-15);          // -2y < -0.6: y > 0.3
  EXPECT_NEAR(plane_volume(1, 1, 0, 0.5), 0.125, 1e-15);          // triangle x + y < 1/2
  EXPECT_NEAR(plane_volume(1, 1, 1, 0.5), 0.125 / 6, 1e-15);      // corner tetrahedron
  EXPECT_NEAR(plane_volume(1, 1, 1, 1.5), 0.5, 1e-15);            // through the centre
  EXPECT_NEAR(plane_volume(1, 1, 1, 2.5), 1 - 0.125 / 6, 1e-15);  // the opposite corner cut off
  EXPECT_EQ(plane_volume(1, 2, 3, -0.1), 0.0);
  EXPECT_EQ(plane_volume(1, 2, 3, 6.1), 1.0);
}

TEST(Plic, ComplementAndInverse) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1), uf(0, 1);
  double worst = 0;
  for (int t = 0; t < 20000; ++t) {
    double n[3] = {u(rng), u(rng), u(rng)};
    // Degenerate normals: zeros and tiny components, as an axis-aligned interface gives.
    if (t % 5 == 1) n[t % 3] = 0;
    if (t % 7 == 2) n[(t + 1) % 3] = 1e-13 * n[(t + 1) % 3];
    if (t % 11 == 3) n[0] = n[1] = 0;
    if (n[0] == 0 && n[1] == 0 && n[2] == 0) continue;  // no plane
    const double f = t % 13 == 0 ? 1e-10 : (t % 17 == 0 ? 1 - 1e-10 : uf(rng));
    const double alpha = plane_alpha(n[0], n[1], n[2], f);
    const double err = std::abs(plane_volume(n[0], n[1], n[2], alpha) - f);
    EXPECT_LT(err, 1e-13) << n[0] << " " << n[1] << " " << n[2] << " f " << f;
    worst = std::max(worst, err);
    // The two sides of one plane fill the cube.
    EXPECT_NEAR(plane_volume(n[0], n[1], n[2], alpha) + plane_volume(-n[0], -n[1], -n[2], -alpha), 1.0, 1e-14);
  }
  EXPECT_LT(worst, 1e-13);
}

TEST(Plic, MonotoneInAlpha) {
  const double n[3] = {0.3, -0.8, 0.1};
  double last = 0;
  for (int i = 0; i <= 1000; ++i) {
    const double a = -1.0 + 2.5 * i / 1000;
    const double v = plane_volume(n[0], n[1], n[2], a);
    EXPECT_GE(v, last - 1e-15);
    last = v;
  }
}

TEST(Plic, SlabAgainstPointCounting) {
  // The liquid in the slab x_d in [1 - s, 1] (or [0, s]) of a cell cut by a plane, counted on a
  // 200^3 lattice of points: agreement to the lattice's resolution.
  const double n[3] = {0.6, -0.3, 0.5};
  const double alpha = plane_alpha(n[0], n[1], n[2], 0.42);
  const int m = 200;
  for (int d = 0; d < 3; ++d)
    for (int high = 0; high < 2; ++high) {
      const double s = 0.37;
      long inside = 0;
      for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b)
          for (int c = 0; c < m; ++c) {
            double x[3] = {(a + 0.5) / m, (b + 0.5) / m, (c + 0.5) / m};
            const bool in_slab = high ? x[d] >= 1 - s : x[d] <= s;
            if (in_slab && n[0] * x[0] + n[1] * x[1] + n[2] * x[2] < alpha) ++inside;
          }
      const double counted = double(inside) / (double(m) * m * m);
      EXPECT_NEAR(slab_volume(n, alpha, d, s, high), counted, 2e-3) << "d " << d << " high " << high;
    }
  // The whole cell as a slab is the cell's volume; an empty slab carries nothing.
  EXPECT_NEAR(slab_volume(n, alpha, 1, 1.0, true), 0.42, 1e-14);
  EXPECT_EQ(slab_volume(n, alpha, 1, 0.0, false), 0.0);
}
