// SPDX-License-Identifier: MIT
// The shaped bodies' elements are placed at x_i + R(q_i) c_e whichever way they are placed: all of
// them (place), a listed few (place_listed, which must leave the others alone), or one asked for
// from the bodies' poses (position).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "solid/contact_entities.hpp"

namespace tessera {
namespace {

TEST(ContactEntities, PlacingTheListedElementsPlacesThemAsAllAreAndLeavesTheRest) {
  ShapeTemplate grain;
  grain.spheres = {{1e-3, 0, 0}, {-1e-3, 0, 0}, {0, 4e-4, 0}, {0, 0, -4e-4}, {3e-4, 2e-4, 1e-4}};
  grain.sphere_radius = 2e-4;
  grain.bounding_radius = 1.2e-3;
  const std::vector<ShapeTemplate> shapes{grain};
  ParticleStore p;
  for (int i = 0; i < 4; ++i) {
    p.push_back(i, 0, grain.bounding_radius, 1.0, 1.0, {0.01 * i, 0.002 * i, -0.003 * i}, {}, {});
    p.order[static_cast<std::size_t>(i)] = i;
    p.shape[static_cast<std::size_t>(i)] = i == 2 ? 0 : 1;  // one plain sphere among the grains
  }
  p.radius[2] = 5e-4;
  p.owned = 3, p.ghosts = 1;
  auto turn = [&](std::size_t i, double a) {  // a unit quaternion about (1, 2, 2) / 3
    const double s = std::sin(0.5 * a) / 3.0;
    p.q[4 * i] = std::cos(0.5 * a), p.q[4 * i + 1] = s, p.q[4 * i + 2] = 2 * s, p.q[4 * i + 3] = 2 * s;
  };
  for (std::size_t i = 0; i < 4; ++i) turn(i, 0.3 + i);
  ContactEntities entities(p);
  entities.configure(true, -1);
  entities.layout(shapes, 8);
  ASSERT_EQ(entities.size(), 3 * grain.spheres.size() + 1);
  EXPECT_DOUBLE_EQ(entities.element_reach(0), grain.bounding_radius);
  EXPECT_DOUBLE_EQ(entities.element_reach(2), 5e-4);
  const std::vector<KernelGeometry> before = entities.geometry_mirrors();

  // The bodies move and turn; elements 1, 6, 10 (the sphere) and 12 (a ghost's) are placed alone.
  for (std::size_t i = 0; i < 4; ++i) {
    p.x[3 * i] += 1e-4 * (i + 1), p.x[3 * i + 2] -= 3e-5;
    turn(i, 1.1 + 0.7 * i);
  }
  const std::vector<std::int32_t> listed{1, 6, 10, 12};
  entities.place_listed(shapes, listed.data(), listed.data() + listed.size());
  const std::vector<KernelGeometry> some = entities.geometry_mirrors();
  entities.place(shapes, 0, p.size());
  const std::vector<KernelGeometry>& all = entities.geometry_mirrors();
  for (std::size_t e = 0; e < entities.size(); ++e) {
    const bool is_listed = e == 1 || e == 6 || e == 10 || e == 12;
    const KernelGeometry& want = is_listed ? all[e] : before[e];
    EXPECT_EQ(some[e].x, want.x) << e;  // the same bits: the same expression
    EXPECT_EQ(some[e].y, want.y) << e;
    EXPECT_EQ(some[e].z, want.z) << e;
    EXPECT_EQ(some[e].r, want.r) << e;
    const Vec3 at = entities.position(shapes, e);
    EXPECT_EQ(at.x, all[e].x) << e;
    EXPECT_EQ(at.y, all[e].y) << e;
    EXPECT_EQ(at.z, all[e].z) << e;
  }
  EXPECT_NE(before[1].x, all[1].x);  // they did move
}

}  // namespace
}  // namespace tessera
