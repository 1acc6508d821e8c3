// SPDX-License-Identifier: MIT
// Tetrahedron-box clipping (src/coupling/tet_clip.hpp, theory C1) against closed-form volumes of
// the unit corner tetrahedron x, y, z >= 0, x + y + z <= 1, a Monte Carlo count for an arbitrary
// tetrahedron laid over a grid, and a convex body swept whole against its tetrahedra one by one.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "coupling/tet_clip.hpp"
#include "solid/shape.hpp"

using namespace tessera;

namespace {

const Tet kCorner{Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};

double clipped(const Tet& t, int axis, double value, bool below) {
  std::vector<Tet> out;
  clip_tets({t}, axis, value, below, out);
  double v = 0;
  for (const Tet& p : out) v += tet_volume(p);
  return v;
}

// Volume of the corner tetrahedron inside the cube [0, a]^3: the cube less the corner beyond the
// plane x + y + z = 1, plus the three corners counted twice once 2a > 1 (inclusion-exclusion).
double corner_in_cube(double a) {
  auto cube = [](double s) { return s > 0 ? s * s * s / 6 : 0.0; };
  if (a >= 1) return 1.0 / 6;  // the whole tetrahedron
  return a * a * a - cube(3 * a - 1) + 3 * cube(2 * a - 1);
}

bool in_tet(const Tet& t, const Vec3& p) {
  // Same side of each face as the opposite vertex.
  const int f[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};
  for (const auto& face : f) {
    const Vec3 n = cross(t[face[1]] - t[face[0]], t[face[2]] - t[face[0]]);
    if (dot(n, p - t[face[0]]) * dot(n, t[face[3]] - t[face[0]]) < 0) return false;
  }
  return true;
}

}  // namespace

TEST(TetClip, SlabOfTheCornerTetrahedron) {
  // x_d <= a keeps 1/6 (1 - (1 - a)^3); x_d >= a keeps (1 - a)^3 / 6.
  for (int d = 0; d < 3; ++d)
    for (double a : {0.0, 0.1, 0.25, 1.0 / 3, 0.5, 0.77, 0.999, 1.0, 1.5}) {
      const double rest = std::pow(std::max(0.0, 1 - a), 3) / 6;
      EXPECT_NEAR(clipped(kCorner, d, a, true), 1.0 / 6 - rest, 1e-16) << d << " " << a;
      EXPECT_NEAR(clipped(kCorner, d, a, false), rest, 1e-16) << d << " " << a;
    }
}

TEST(TetClip, CornerTetrahedronInCubes) {
  // The three regimes: cube inside (a <= 1/3), one corner cut off (<= 1/2), three edges back (<= 1).
  for (double a : {0.2, 1.0 / 3, 0.4, 0.5, 0.6, 0.75, 0.9, 1.0, 1.3}) {
    EXPECT_NEAR(tet_box_volume(kCorner, {0, 0, 0}, {a, a, a}), corner_in_cube(a), 1e-15) << a;
    // The same shape moved, scaled by 2 and with its vertex order turned.
    const Tet moved{Vec3{3, 1, 2}, Vec3{5, 1, 2}, Vec3{3, 1, 4}, Vec3{3, 3, 2}};
    EXPECT_NEAR(tet_box_volume(moved, {3, 1, 2}, {3 + 2 * a, 1 + 2 * a, 2 + 2 * a}), 8 * corner_in_cube(a), 1e-13)
        << a;
  }
}

TEST(TetClip, RasterizedPiecesSumToTheTetrahedronAndMatchEachBox) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const CellRange grid{{-1.3, -1.1, -1.2}, {0.31, 0.27, 0.41}, {0, 0, 0}, {9, 9, 7}};
  CellRasterizer raster;
  for (int n = 0; n < 200; ++n) {
    Tet t;
    for (auto& p : t) p = {u(rng), u(rng), u(rng)};
    std::map<std::array<int, 3>, double> cells;
    raster.overlaps(t, grid, [&](int i, int j, int k, double v) {
      const bool fresh = cells.emplace(std::array<int, 3>{i, j, k}, v).second;
      EXPECT_TRUE(fresh) << "cell visited twice";
    });
    double total = 0;
    for (const auto& [idx, v] : cells) {
      total += v;
      const Vec3 lo{grid.lo.x + idx[0] * grid.h[0], grid.lo.y + idx[1] * grid.h[1], grid.lo.z + idx[2] * grid.h[2]};
      const Vec3 hi = lo + Vec3{grid.h[0], grid.h[1], grid.h[2]};
      EXPECT_NEAR(v, tet_box_volume(t, lo, hi), 1e-14);
    }
    EXPECT_NEAR(total, tet_volume(t), 1e-14 * (1 + tet_volume(t)));
  }
}

TEST(TetClip, RasterizedVolumesAgreeWithMonteCarlo) {
  // An independent count: 2 million uniform points in the tetrahedron's bounding box.
  const Tet t{Vec3{0.05, 0.1, 0.0}, Vec3{0.93, 0.2, 0.15}, Vec3{0.4, 0.97, 0.3}, Vec3{0.3, 0.35, 0.88}};
  const CellRange grid{{0, 0, 0}, {1.0 / 3, 1.0 / 3, 1.0 / 3}, {0, 0, 0}, {3, 3, 3}};
  std::map<std::array<int, 3>, double> exact;
  CellRasterizer raster;
  raster.overlaps(t, grid, [&](int i, int j, int k, double v) { exact[{i, j, k}] = v; });
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const long n = 2'000'000;
  std::map<std::array<int, 3>, long> hits;
  for (long s = 0; s < n; ++s) {
    const Vec3 p{u(rng), u(rng), u(rng)};
    if (in_tet(t, p)) ++hits[{int(p.x * 3), int(p.y * 3), int(p.z * 3)}];
  }
  ASSERT_GE(exact.size(), 8u);
  for (const auto& [idx, v] : exact) {
    const double p = v, mc = double(hits[idx]) / n;
    const double sigma = std::sqrt(p * (1 - p) / n);
    EXPECT_NEAR(mc, v, 5 * sigma + 1e-7) << idx[0] << idx[1] << idx[2];
  }
  for (const auto& [idx, c] : hits) EXPECT_TRUE(exact.count(idx)) << "a hit outside the rasterized cells";
}

TEST(TetClip, OnlyTheRangeIsVisited) {
  // Cells outside [begin, end) get nothing; the visited ones get their exact share.
  const Tet t{Vec3{0.1, 0.1, 0.1}, Vec3{1.9, 0.2, 0.3}, Vec3{0.5, 1.8, 0.2}, Vec3{0.4, 0.6, 1.7}};
  const CellRange all{{0, 0, 0}, {0.5, 0.5, 0.5}, {0, 0, 0}, {4, 4, 4}};
  CellRange part = all;
  part.begin = {1, 0, 2};
  part.end = {3, 4, 4};
  CellRasterizer raster;
  double sum_part = 0, sum_all_in_part = 0;
  raster.overlaps(t, part, [&](int i, int, int k, double v) {
    EXPECT_TRUE(i >= 1 && i < 3 && k >= 2);
    sum_part += v;
  });
  raster.overlaps(t, all, [&](int i, int, int k, double v) {
    if (i >= 1 && i < 3 && k >= 2) sum_all_in_part += v;
  });
  EXPECT_GT(sum_part, 0);
  EXPECT_NEAR(sum_part, sum_all_in_part, 1e-15);
}

TEST(TetClip, FirstAndLastCellsTakeWhatLiesBeyondThem) {
  // Random tetrahedra over a 4 x 3 x 5 grid, most reaching past it: along x and z the grid's
  // first and last cells reach beyond it (walls), along y not (an open side). Each cell then gets
  // its share of the tetrahedron clipped to the cell's box stretched to infinity on the walls'
  // sides (an independent computation with tet_box_volume), and the cells' sum is the whole
  // tetrahedron less what lies beyond the open side.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.6, 1.6);
  CellRange grid{{0, 0, 0}, {0.25, 1.0 / 3, 0.2}, {0, 0, 0}, {4, 3, 5}};
  grid.first = {0, INT_MIN, 0};
  grid.last = {3, INT_MAX, 4};
  const double far = 1e3;
  CellRasterizer raster;
  for (int n = 0; n < 200; ++n) {
    Tet t;
    for (auto& p : t) p = {u(rng), u(rng), u(rng)};
    double total = 0;
    raster.overlaps(t, grid, [&](int i, int j, int k, double v) {
      const int idx[3] = {i, j, k};
      Vec3 lo, hi;
      for (int d = 0; d < 3; ++d) {
        lo[d] = grid.lo[d] + idx[d] * grid.h[d];
        hi[d] = lo[d] + grid.h[d];
        if (d != 1 && idx[d] == 0) lo[d] = -far;
        if (d != 1 && idx[d] == grid.end[d] - 1) hi[d] = far;
      }
      EXPECT_NEAR(v, tet_box_volume(t, lo, hi), 1e-13) << i << " " << j << " " << k;
      total += v;
    });
    EXPECT_NEAR(total, tet_box_volume(t, {-far, 0, -far}, {far, 1, far}), 1e-13);
  }
}

TEST(TetClip, AConvexBodySweptWholeGivesEachCellItsTetrahedra) {
  // The drop-on-sand grain (a 1.27 x 0.52 spheroid's fan mesh, in mm) at random poses over cells of
  // 0.19 mm, walls along z: laid out as the one polytope its surface bounds, every cell gets what its
  // 90 tetrahedra give it one by one (to round-off), the cells sum to the mesh's volume, and a
  // sub-range's cells get the same bits.
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  ellipsoid_mesh({0.635, 0.26, 0.26}, 5, 9, nodes, tets);
  const auto surface = boundary_triangles(nodes, tets);
  double volume = 0;
  for (const auto& t : tets) volume += tet_volume(Tet{nodes[t[0]], nodes[t[1]], nodes[t[2]], nodes[t[3]]});
  ASSERT_TRUE(bounds_convex_polytope(nodes, surface, volume));
  CellRange grid{{-1, -1, -1}, {0.19, 0.19, 0.19}, {0, 0, 0}, {11, 11, 11}};
  grid.first[2] = 0;
  grid.last[2] = 10;
  CellRange part = grid;
  part.begin = {3, 0, 4};
  part.end = {7, 11, 11};
  const double cell = 0.19 * 0.19 * 0.19;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  CellRasterizer raster;
  Polytope body;
  std::vector<Vec3> world(nodes.size());
  int pieces = 0;
  for (int n = 0; n < 100; ++n) {
    double q[4] = {n01(rng), n01(rng), n01(rng), n01(rng)};
    const double l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (double& c : q) c /= l;
    // A body near the walls now and then: its part beyond them goes to the first and last cells.
    const Vec3 centre{u(rng), u(rng), n % 4 == 0 ? -0.95 : u(rng)};
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const Vec3& p = nodes[k];
      const Vec3 v{q[1], q[2], q[3]};
      const Vec3 t = 2.0 * cross(v, p);
      world[k] = centre + p + q[0] * t + cross(v, t);
    }
    std::map<std::array<int, 3>, double> by_tets, whole, in_part;
    for (const auto& t : tets)
      raster.overlaps(Tet{world[t[0]], world[t[1]], world[t[2]], world[t[3]]}, grid,
                      [&](int i, int j, int k, double v) { by_tets[{i, j, k}] += v; });
    body.set_triangles(world, surface);
    double total = 0;
    raster.overlaps(body, grid, [&](int i, int j, int k, double v) {
      EXPECT_TRUE(whole.emplace(std::array<int, 3>{i, j, k}, v).second) << "cell visited twice";
      total += v;
    });
    for (const auto& [idx, v] : by_tets) {
      const auto it = whole.find(idx);
      EXPECT_NEAR(it == whole.end() ? 0.0 : it->second, v, 1e-13 * cell) << n << ": " << idx[0] << idx[1] << idx[2];
    }
    for (const auto& [idx, v] : whole) EXPECT_TRUE(by_tets.count(idx) || v < 1e-13 * cell);
    EXPECT_NEAR(total, volume, 1e-13 * volume);
    raster.overlaps(body, part, [&](int i, int j, int k, double v) { in_part[{i, j, k}] = v; });
    for (const auto& [idx, v] : in_part) EXPECT_EQ(v, whole.at(idx));
    for (const auto& [idx, v] : whole) {
      if (idx[0] >= 3 && idx[0] < 7 && idx[2] >= 4) {
        EXPECT_TRUE(in_part.count(idx));
      }
    }
    pieces += int(whole.size());
  }
  EXPECT_GT(pieces, 100 * 20);  // the grain spans tens of cells: the sweep is exercised
}
