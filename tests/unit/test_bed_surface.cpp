// SPDX-License-Identifier: MIT
// The crater measures (theory D2-D5) on surfaces whose crater is known in closed form: a spherical
// cap of depth H0 and radius L0 cut into a flat bed at z0, ringed by a flat-topped rim of height
// rim. The grains are points on a fine lattice (spacing 0.025 mm, a quarter of the smoothing cell)
// whose tops lie on that surface. Eq. 14 must give the cap of height H0 + rim and base radius L0;
// the tolerances are the discretisation's bounds, stated with each check.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "analysis/bed_surface.hpp"

namespace tessera {
namespace {

constexpr double mm = 1e-3;
constexpr double z0 = 8 * mm, H0 = 1.5 * mm, L0 = 6.05 * mm, rim = 0.5 * mm;
constexpr double cell = 0.1 * mm, dr = 0.1 * mm;
const double R = (L0 * L0 + H0 * H0) / (2 * H0);  // the cap's sphere

// Height of the surface at radius r: the cap inside L0, the rim's plateau over
// [L0 - dr/2 - cell, L0 + dr/2 + cell] (every point of the cells whose centres lie in the ring at
// L0 is on it), the flat bed beyond.
double surface(double r) {
  if (r >= L0 - 0.5 * dr - cell && r <= L0 + 0.5 * dr + cell) return z0 + rim;
  if (r < L0) return z0 - (std::sqrt(R * R - r * r) - (R - H0));
  return z0;
}

std::vector<GrainTop> lattice(double cx, double cy, double below = -1) {
  std::vector<GrainTop> tops;
  const double step = 0.025 * mm, half = 8 * mm;
  for (double y = -half + step / 2; y < half; y += step)
    for (double x = -half + step / 2; x < half; x += step) {
      const double h = surface(std::hypot(x, y));
      tops.push_back({cx + x, cy + y, h});
      if (below > 0) tops.push_back({cx + x, cy + y, h - below});  // a buried grain under each
    }
  return tops;
}

CraterSettings settings(double cx, double cy, double layer) {
  CraterSettings s;
  s.cx = cx, s.cy = cy, s.cell = cell, s.ring_width = dr, s.surface_layer = layer, s.max_radius = 7.5 * mm;
  return s;
}

double cap_volume(double h, double base_radius) {
  return std::numbers::pi * h * (3 * base_radius * base_radius + h * h) / 6;
}

TEST(BedSurface, Eq14RecoversTheCapOfAKnownCrater) {
  const double cx = 16.9 * mm, cy = 16.9 * mm;
  const Crater c = measure_crater(lattice(cx, cy), settings(cx, cy, 1.0));
  ASSERT_TRUE(c.valid);
  // a: the ring at L0 lies wholly on the rim's plateau.
  EXPECT_NEAR(c.a, z0 + rim, 1e-12);
  EXPECT_NEAR(c.rim_radius, L0, 1e-12);
  // b: the axis cell's mean; the cap rises by r^2 / (2 R) <= (cell^2 / 2) / (2 R) over the cell.
  const double rise = 0.5 * cell * cell / (2 * R);
  EXPECT_GE(c.b, z0 - H0 - 1e-12);
  EXPECT_LE(c.b, z0 - H0 + rise);
  // V: the cap of height H0 + rim (rise / H changes it by less than 2 rise / H).
  const double V = cap_volume(H0 + rim, L0);
  EXPECT_NEAR(c.volume, V, 2 * rise / (H0 + rim) * V + 1e-18);
  EXPECT_GT(c.volume, 0.9 * V);  // and not near it by a wide tolerance
}

TEST(BedSurface, SectionsFindTheRimsWithinACell) {
  const double cx = 10 * mm, cy = 12 * mm;
  const Crater c = measure_crater(lattice(cx, cy), settings(cx, cy, 1.0));
  ASSERT_TRUE(c.valid);
  // The innermost cell wholly on the plateau is within dr/2 + cell of L0 on each side.
  for (const CraterSection* s : {&c.section_x, &c.section_y}) {
    EXPECT_NEAR(s->a1, z0 + rim, 1e-12);
    EXPECT_NEAR(s->a2, z0 + rim, 1e-12);
    EXPECT_NEAR(s->length, 2 * L0, 2 * (0.5 * dr + cell) + 1e-12);
    EXPECT_LE(s->length, 2 * L0);
    EXPECT_NEAR(s->b, c.b, 1e-12);  // the axis cell
  }
  // Eq. 13 with l = L1 = L2 (l / 2 plays L0): within the bound the rim positions allow.
  const double l_lo = 2 * L0 - 2 * (0.5 * dr + cell);
  EXPECT_LE(c.section_volume, cap_volume(H0 + rim, L0) * 1.001);
  EXPECT_GE(c.section_volume, cap_volume(H0 + rim - 0.001 * mm, l_lo / 2));
}

TEST(BedSurface, SurfaceLayerKeepsOnlyTheTopGrains) {
  const double cx = 16.9 * mm, cy = 16.9 * mm;
  // A buried grain 1 mm under every surface grain: a 0.5 mm layer ignores them...
  const Crater top = measure_crater(lattice(cx, cy), settings(cx, cy, 0.5 * mm));
  const Crater layered = measure_crater(lattice(cx, cy, 1 * mm), settings(cx, cy, 0.5 * mm));
  EXPECT_DOUBLE_EQ(layered.volume, top.volume);
  EXPECT_DOUBLE_EQ(layered.b, top.b);
  // ... an unbounded one averages them in (every height 0.5 mm lower, the depth unchanged).
  const Crater column = measure_crater(lattice(cx, cy, 1 * mm), settings(cx, cy, 1.0));
  EXPECT_NEAR(column.b, top.b - 0.5 * mm, 1e-12);
  EXPECT_NEAR(column.depth, top.depth, 1e-12);
}

TEST(BedSurface, FlatBedHasNoCrater) {
  std::vector<GrainTop> tops;
  for (int j = 0; j < 200; ++j)
    for (int i = 0; i < 200; ++i) tops.push_back({i * 0.1 * mm, j * 0.1 * mm, z0});
  const Crater c = measure_crater(tops, settings(10 * mm, 10 * mm, 1.0));
  EXPECT_NEAR(c.depth, 0.0, 1e-15);  // round-off of the means
  EXPECT_NEAR(c.volume, 0.0, 1e-20);
}

TEST(BedSurface, BedTopIsTheHighestNearTheAxis) {
  const std::vector<GrainTop> tops{{0, 0, 1.0}, {0.5e-3, 0, 2.0}, {2e-3, 0, 5.0}};
  EXPECT_DOUBLE_EQ(bed_top(tops, 0, 0, 1e-3), 2.0);
  EXPECT_DOUBLE_EQ(bed_top(tops, 0, 0, 3e-3), 5.0);
  EXPECT_TRUE(std::isinf(bed_top(tops, 10, 10, 1e-3)));
}

}  // namespace
}  // namespace tessera
