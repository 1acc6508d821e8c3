// SPDX-License-Identifier: MIT
// Mass properties from tetrahedra (T10) against closed forms: a cube (Kuhn's 6 tetrahedra), a
// rotated and shifted box (principal moments and axes), and a spheroid whose faceted volume and
// inertia converge to the analytic values at second order as the mesh is refined.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "solid/rigid_rotation.hpp"
#include "solid/tet_mass_properties.hpp"
#include "support/meshes.hpp"

namespace tessera {
namespace {

// Box [0,a]x[0,b]x[0,c] as Kuhn's 6 tetrahedra around the main diagonal.
void box(double a, double b, double c, std::vector<Vec3>& nodes, std::vector<std::array<int, 4>>& tets) {
  for (int v = 0; v < 8; ++v) nodes.push_back({(v & 1) ? a : 0.0, (v & 2) ? b : 0.0, (v & 4) ? c : 0.0});
  const int axis_bits[3] = {1, 2, 4};
  int perm[3] = {0, 1, 2};
  do {
    const int p1 = axis_bits[perm[0]], p2 = p1 | axis_bits[perm[1]];
    tets.push_back({0, p1, p2, 7});
  } while (std::next_permutation(perm, perm + 3));
}

TEST(TetMassProperties, CubeOfSixTetrahedra) {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  box(1, 1, 1, nodes, tets);
  const MassProperties mp = tet_mass_properties(nodes, tets, 2.0);
  EXPECT_NEAR(mp.volume, 1.0, 1e-15);
  EXPECT_NEAR(mp.mass, 2.0, 1e-15);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(mp.centroid[d], 0.5, 1e-15);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(mp.inertia[i][j], i == j ? 2.0 / 6.0 : 0.0, 1e-14);
}

TEST(TetMassProperties, RotatedBoxPrincipalMomentsAndAxes) {
  const double a = 1.0, b = 2.0, c = 3.0, rho = 1.5;
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  box(a, b, c, nodes, tets);
  // Rotate by a known quaternion and shift.
  const double h = 0.5 * 0.7;
  const Vec3 axis = Vec3{1, 2, 2} / 3.0;
  const Quaternion q{std::cos(h), std::sin(h) * axis.x, std::sin(h) * axis.y, std::sin(h) * axis.z};
  for (auto& p : nodes) p = q.rotate(p) + Vec3{5, -3, 7};
  const MassProperties mp = tet_mass_properties(nodes, tets, rho);
  const double m = rho * a * b * c;
  EXPECT_NEAR(mp.mass, m, 1e-13);
  const Vec3 centre = q.rotate({a / 2, b / 2, c / 2}) + Vec3{5, -3, 7};
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(mp.centroid[d], centre[d], 1e-13);
  // Ascending: about the c-edge axis (z), then b (y), then a (x).
  const double expected[3] = {m * (a * a + b * b) / 12, m * (a * a + c * c) / 12, m * (b * b + c * c) / 12};
  const Vec3 expected_axes[3] = {q.rotate({0, 0, 1}), q.rotate({0, 1, 0}), q.rotate({1, 0, 0})};
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(mp.principal_moments[k], expected[k], 1e-12);
    EXPECT_NEAR(std::fabs(dot(mp.principal_axes[k], expected_axes[k])), 1.0, 1e-12);
  }
  EXPECT_NEAR(dot(cross(mp.principal_axes[0], mp.principal_axes[1]), mp.principal_axes[2]), 1.0, 1e-12);
}

// The spheroid (tests/support/meshes.hpp): the faceted body's volume and inertia converge to
// 4/3 pi a b c and m (b^2 + c^2) / 5 at second order in the mesh size.
TEST(TetMassProperties, SpheroidConvergesAtSecondOrder) {
  const double ax = 0.635e-3, r = 0.26e-3, rho = 2650;  // the seed's grain: 1.27 x 0.52 mm
  const double v_exact = 4.0 / 3.0 * std::numbers::pi * ax * r * r;
  const double i_axial = rho * v_exact * (2 * r * r) / 5, i_transverse = rho * v_exact * (ax * ax + r * r) / 5;
  double previous_error = 0;
  for (int n : {8, 16, 32, 64}) {
    std::vector<Vec3> nodes;
    std::vector<std::array<int, 4>> tets;
    test::spheroid_fan(ax, r, n, nodes, tets);
    const MassProperties mp = tet_mass_properties(nodes, tets, rho);
    const double err = std::max({std::fabs(mp.volume / v_exact - 1), std::fabs(mp.principal_moments[0] / i_axial - 1),
                                 std::fabs(mp.principal_moments[2] / i_transverse - 1)});
    std::printf("  n_lat %2d: %5zu tetrahedra, relative error %.3e%s\n", n, tets.size(), err,
                previous_error > 0 ? (", order " + std::to_string(std::log2(previous_error / err))).c_str() : "");
    if (previous_error > 0) {
      EXPECT_GT(std::log2(previous_error / err), 1.8);
    }
    previous_error = err;
    EXPECT_NEAR(std::fabs(mp.principal_axes[0].x), 1.0, 1e-9);  // the long axis has the smallest moment
  }
  EXPECT_LT(previous_error, 2e-3);
}

}  // namespace
}  // namespace tessera
