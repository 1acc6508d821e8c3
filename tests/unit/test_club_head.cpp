// SPDX-License-Identifier: MIT
// The bunker-shot club head (src/solid/club_head.hpp): face length and loft, the sole's bounce,
// the seed's six sole samples, the outline's orientation and the extruded surface's normals.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/config.hpp"
#include "solid/club_head.hpp"
#include "solid/contact_model.hpp"
#include "solid/walls.hpp"

using namespace tessera;

TEST(ClubHead, FaceLoftBounceAndSoleSamples) {
  for (double loft : {56.0, 58.0, 60.0, 65.0})
    for (double bounce : {7.0, 10.0, 13.0}) {
      ClubHeadDesign d;
      d.loft_deg = loft;
      d.bounce_deg = bounce;
      const auto o = club_head_outline(d);
      ASSERT_EQ(o.size(), 7u);  // L, F, and the sole at t = 1, 0.8, ..., 0.2 (seed: 6 points, L shared)
      // Face: 65 mm from the leading edge, leaning back from the vertical by the loft.
      const double fx = o[1][0] - o[0][0], fz = o[1][1] - o[0][1];
      EXPECT_NEAR(std::hypot(fx, fz), 0.065, 1e-15);
      EXPECT_NEAR(std::atan2(-fx, fz) * 180 / std::numbers::pi, loft, 1e-12);
      // Sole: its chord from the leading to the trailing edge goes back and down at the bounce
      // angle (the sole hangs below the leading edge), 20 mm long, bulging 1 mm below the chord.
      const auto T = club_sole_point(d, 1);
      EXPECT_NEAR(std::atan2(-T[1], -T[0]) * 180 / std::numbers::pi, bounce, 1e-12);
      EXPECT_NEAR(std::hypot(T[0], T[1]), 0.020, 1e-15);
      const auto mid = club_sole_point(d, 0.5);
      const double b = bounce * std::numbers::pi / 180;
      EXPECT_NEAR(mid[0] * std::sin(b) - mid[1] * std::cos(b), 0.001, 1e-15);  // below the chord
      const auto t0 = club_sole_tangent(d, 0);
      EXPECT_GT(std::atan2(-t0[1], -t0[0]), b);  // the camber steepens the sole at the edge
      // The samples are the Bezier curve's points at t = 0.2 k.
      for (int k = 1; k <= 5; ++k) {
        const auto p = club_sole_point(d, 0.2 * k);
        EXPECT_NEAR(o[2 + (5 - k)][0], p[0], 1e-17);
        EXPECT_NEAR(o[2 + (5 - k)][1], p[1], 1e-17);
      }
      // Counter-clockwise (positive signed area).
      double area = 0;
      for (std::size_t i = 0; i < o.size(); ++i) {
        const auto& a = o[i];
        const auto& b = o[(i + 1) % o.size()];
        area += a[0] * b[1] - b[0] * a[1];
      }
      EXPECT_GT(area, 0);
    }
}

TEST(ClubHead, ExtrudedSurfaceNormalsPointOut) {
  ClubHeadDesign d;
  const auto o = club_head_outline(d);
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 3>> tris;
  extrude_outline(o, 0.3e-3, 0.6e-3, nodes, tris);
  ASSERT_EQ(tris.size(), 2 * o.size());
  // Every triangle's normal points away from the outline's centroid (a convex-enough head: the
  // centroid is inside) and has no component along y.
  Vec3 c;
  for (const auto& p : o) c += Vec3{p[0], 0.3e-3, p[1]};
  c = c / double(o.size());
  for (const auto& t : tris) {
    const Vec3 a = nodes[t[0]], b = nodes[t[1]], e = nodes[t[2]];
    const Vec3 n = cross(b - a, e - a);
    EXPECT_GT(dot(n, (a + b + e) / 3.0 - c), 0);
    EXPECT_NEAR(n.y, 0.0, 1e-18);
  }
}

// A mesh wall `club: {...}` in a case file is that outline, extruded, with its leading edge where
// the case puts it.
TEST(ClubHead, MeshWallFromTheCaseFile) {
  const char* yaml = R"(
solid:
  materials: {sand: {density: 2480}, club: {density: 7800}}
  contact:
    law: hooke
    pairs: [{materials: [sand, club], normal_stiffness: 1e4, tangential_stiffness: 2e3, normal_damping_rate: 0, tangential_damping_rate: 0, friction: 0.2}]
  walls:
    - type: mesh
      material: club
      club: {loft_deg: 60, bounce_deg: 13, leading_edge: [0.1, 0.0003, 0.05], width: 0.0012}
      motion: {type: pivot, pivot: [0.1, 0.0003, 0.75], axis: [0, -1, 0], moment_of_inertia: 0.01}
)";
  Config c = Config::parse(yaml);
  const ConfigNode solid = c.root().section("solid");
  ContactModel model(solid);
  Walls walls(solid, model, ".");
  ASSERT_EQ(walls.meshes().size(), 1u);
  const MeshWall& m = walls.meshes()[0];
  ClubHeadDesign d;
  d.loft_deg = 60;
  d.bounce_deg = 13;
  const auto o = club_head_outline(d);
  ASSERT_EQ(m.triangles.size(), 2 * o.size());
  ASSERT_EQ(m.local.size(), 2 * o.size());
  for (std::size_t i = 0; i < o.size(); ++i) {
    const Vec3 p = m.origin + m.local[2 * i];  // the y- node of outline point i, at theta = 0
    EXPECT_NEAR(p.x, 0.1 + o[i][0], 1e-15);
    EXPECT_NEAR(p.y, 0.0003 - 0.0006, 1e-15);
    EXPECT_NEAR(p.z, 0.05 + o[i][1], 1e-15);
  }
  EXPECT_EQ(m.motion, MeshWall::Motion::pivot);
}
