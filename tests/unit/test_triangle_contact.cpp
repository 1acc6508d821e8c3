// SPDX-License-Identifier: MIT
// Sphere-triangle contacts (T11): closest-feature classification, and no double counting where
// triangles meet: rolling across a shared edge or vertex of coplanar triangles gives the force of
// one plane; a convex ridge gives one contact, a concave valley one per face.
#include <gtest/gtest.h>

#include <cmath>

#include "solid/triangle_contact.hpp"

namespace tessera {
namespace {

TEST(TriangleContact, ClosestFeature) {
  const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  TriangleFeature f;
  Vec3 q = closest_point_on_triangle({0.2, 0.2, 1}, a, b, c, f);
  EXPECT_EQ(f, TriangleFeature::face);
  EXPECT_NEAR(norm(q - Vec3{0.2, 0.2, 0}), 0, 1e-15);
  q = closest_point_on_triangle({0.5, -1, 0.3}, a, b, c, f);
  EXPECT_EQ(f, TriangleFeature::edge);
  EXPECT_NEAR(norm(q - Vec3{0.5, 0, 0}), 0, 1e-15);
  q = closest_point_on_triangle({-1, -1, 0}, a, b, c, f);
  EXPECT_EQ(f, TriangleFeature::vertex);
  EXPECT_NEAR(norm(q - a), 0, 1e-15);
  q = closest_point_on_triangle({1, 1, 0}, a, b, c, f);
  EXPECT_EQ(f, TriangleFeature::edge);  // hypotenuse
  EXPECT_NEAR(norm(q - Vec3{0.5, 0.5, 0}), 0, 1e-15);
}

// A unit square as a fan of 4 triangles around its centre (shared edges and a shared vertex).
struct Fan {
  std::vector<Vec3> nodes{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 0}};
  std::vector<std::array<int, 3>> tris{{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  std::vector<int> all{0, 1, 2, 3};
};

Vec3 linear_force(const std::vector<TriangleContact>& contacts, double k) {
  Vec3 f;
  for (const auto& c : contacts) f += c.normal * (k * c.overlap);
  return f;
}

TEST(TriangleContact, RollingAcrossSharedEdgesAndVertexFeelsOnePlane) {
  const Fan fan;
  const double r = 0.2, h = 0.15, k = 1000;  // overlap 0.05
  int positions = 0;
  for (const auto& [from, to] : {std::pair<Vec3, Vec3>{{0.25, 0.5, h}, {0.75, 0.5, h}},   // through the vertex
                                 std::pair<Vec3, Vec3>{{0.3, 0.2, h}, {0.7, 0.2, h}},     // across two edges
                                 std::pair<Vec3, Vec3>{{0.3, 0.3, h}, {0.7, 0.7, h}}}) {  // along an edge
    for (int s = 0; s <= 200; ++s, ++positions) {
      const Vec3 p = from + (to - from) * (s / 200.0);
      const auto contacts = sphere_mesh_contacts(p, r, fan.nodes, fan.tris, fan.all);
      const Vec3 f = linear_force(contacts, k);
      ASSERT_EQ(contacts.size(), 1u) << p.x << " " << p.y;
      EXPECT_NEAR(f.z, k * (r - h), 1e-12);
      EXPECT_NEAR(std::hypot(f.x, f.y), 0.0, 1e-12);
    }
  }
  EXPECT_EQ(positions, 603);
}

TEST(TriangleContact, ConvexRidgeGivesOneContactConcaveValleyTwo) {
  // Roof: two faces meeting along the x axis at z = 0, sloping down at 45 degrees.
  std::vector<Vec3> roof{{0, 0, 0}, {1, 0, 0}, {0, -1, -1}, {1, -1, -1}, {0, 1, -1}, {1, 1, -1}};
  std::vector<std::array<int, 3>> tris{{0, 1, 2}, {1, 3, 2}, {0, 4, 1}, {1, 4, 5}};
  const std::vector<int> all{0, 1, 2, 3};
  auto ridge = sphere_mesh_contacts({0.5, 0, 0.1}, 0.2, roof, tris, all);
  ASSERT_EQ(ridge.size(), 1u);
  EXPECT_EQ(ridge[0].feature, TriangleFeature::edge);
  EXPECT_NEAR(ridge[0].overlap, 0.1, 1e-15);
  // The same faces upside down are a valley: a sphere resting in it touches both faces.
  for (auto& v : roof) v.z = -v.z;
  const double r = 0.2, d = r - 0.05;  // centre at distance d from both faces
  auto valley = sphere_mesh_contacts({0.5, 0, d * std::sqrt(2.0)}, r, roof, tris, all);
  ASSERT_EQ(valley.size(), 2u);
  for (const auto& c : valley) {
    EXPECT_EQ(c.feature, TriangleFeature::face);
    EXPECT_NEAR(c.overlap, 0.05, 1e-12);
  }
  const Vec3 f = linear_force(valley, 1.0);
  EXPECT_NEAR(f.y, 0.0, 1e-15);  // symmetric
  EXPECT_NEAR(f.z, 2 * 0.05 / std::sqrt(2.0), 1e-12);
}

}  // namespace
}  // namespace tessera
