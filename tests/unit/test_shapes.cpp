// SPDX-License-Identifier: MIT
// Shape templates (T13): the ellipsoid generator's mesh, the principal frame, the seed's grain, and
// the case-file errors a user can make.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "solid/shape.hpp"
#include "solid/tet_mass_properties.hpp"

namespace tessera {
namespace {

TEST(Shapes, EllipsoidMeshIsAClosedInscribedSurface) {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  ellipsoid_mesh({0.635e-3, 0.26e-3, 0.26e-3}, 5, 9, nodes, tets);
  EXPECT_EQ(nodes.size(), 48u);  // 3 + rings x segments
  EXPECT_EQ(tets.size(), 90u);   // 2 x segments x rings
  const auto surface = boundary_triangles(nodes, tets);
  EXPECT_EQ(surface.size(), 90u);  // every tetrahedron has one face on the surface
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : surface)
    for (int k = 0; k < 3; ++k) ++edges[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
  for (const auto& [e, n] : edges) EXPECT_EQ(n, 2);  // closed, manifold
  for (std::size_t v = 1; v < nodes.size(); ++v) {
    const Vec3& p = nodes[v];
    EXPECT_NEAR(p.x * p.x / (0.635e-3 * 0.635e-3) + (p.y * p.y + p.z * p.z) / (0.26e-3 * 0.26e-3), 1.0, 1e-12);
  }
  const double smooth = 4.0 / 3.0 * std::numbers::pi * 0.635e-3 * 0.26e-3 * 0.26e-3;
  const double v = tet_mass_properties(nodes, tets, 1.0).volume;
  EXPECT_LT(v, smooth);  // inscribed
  EXPECT_NEAR(v / smooth, 0.8765, 1e-3);
}

TEST(Shapes, TemplateLivesInItsPrincipalFrame) {
  // A shifted, turned ellipsoid: the template's frame puts the centroid at 0, the long axis on x
  // (smallest moment first), and its spheres inside the bounding radius.
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  ellipsoid_mesh({3e-3, 2e-3, 1e-3}, 8, 16, nodes, tets);
  for (auto& p : nodes) p = Vec3{p.y + 5e-3, -p.x - 2e-3, p.z + 1e-3};  // turned 90 deg about z, shifted
  const ShapeTemplate t = ShapeTemplate::from_mesh("e", nodes, tets, 30, 0.4e-3);
  const MassProperties mp = tet_mass_properties(t.nodes, t.tetrahedra, 1.0);
  EXPECT_LT(norm(mp.centroid), 1e-15);
  EXPECT_NEAR(mp.inertia[0][1], 0.0, 1e-12 * mp.principal_moments.z);
  EXPECT_NEAR(mp.inertia[0][2], 0.0, 1e-12 * mp.principal_moments.z);
  EXPECT_NEAR(mp.inertia[1][2], 0.0, 1e-12 * mp.principal_moments.z);
  EXPECT_LT(t.inertia_per_density.x, t.inertia_per_density.y);
  EXPECT_LT(t.inertia_per_density.y, t.inertia_per_density.z);
  double extent_x = 0;
  for (const auto& p : t.nodes) extent_x = std::max(extent_x, std::fabs(p.x));
  EXPECT_NEAR(extent_x, 3e-3, 1e-12);  // the long axis is the body's x
  ASSERT_EQ(t.spheres.size(), 30u);
  for (const auto& c : t.spheres) EXPECT_LE(norm(c) + t.sphere_radius, t.bounding_radius * (1 + 1e-12));
}

std::string shape_case(const std::string& shape) { return "solid:\n  shapes:\n    - " + shape + "\n"; }

std::string shape_error(const std::string& shape) {
  try {
    Config c = Config::parse(shape_case(shape));
    read_shapes(c.root().section("solid"), ".");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Shapes, CaseFileErrorsNameTheKey) {
  const std::string grain = "spheroid: {semi_axes: [0.635 mm, 0.26 mm, 0.26 mm]}";
  Config ok = Config::parse(shape_case("{name: grain, " + grain + ", contact_spheres: {count: 75, radius: 0.1 mm}}"));
  const auto shapes = read_shapes(ok.root().section("solid"), ".");
  ASSERT_EQ(shapes.size(), 1u);
  EXPECT_EQ(shapes[0].spheres.size(), 75u);
  // Spheres larger than the tips' radius of curvature poke out.
  EXPECT_NE(shape_error("{name: g, " + grain + ", contact_spheres: {count: 75, radius: 0.25 mm}}")
                .find("contact_spheres.radius"),
            std::string::npos);
  // More spheres than candidate anchors.
  EXPECT_NE(
      shape_error("{name: g, " + grain + ", contact_spheres: {count: 500, radius: 0.1 mm}}").find("contact_spheres"),
      std::string::npos);
  // Neither or both sources.
  EXPECT_NE(shape_error("{name: g, contact_spheres: {count: 5, radius: 0.1 mm}}").find("mesh"), std::string::npos);
  // The reserved name.
  EXPECT_NE(shape_error("{name: sphere, " + grain + ", contact_spheres: {count: 5, radius: 0.1 mm}}").find("name"),
            std::string::npos);
  // A missing mesh file names the file.
  EXPECT_NE(shape_error("{name: g, mesh: nowhere.msh, contact_spheres: {count: 5, radius: 0.1 mm}}").find("nowhere"),
            std::string::npos);
}

TEST(Shapes, ConvexSurfacesAreTold) {
  // A spheroid's fan mesh bounds a convex polytope (its lat-long quads are planar trapezoids); the
  // same mesh with one surface node pulled in, and an L of two tetrahedra, do not. The solid
  // fraction lays only the first out whole (coupling/solid_phase.cpp).
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  ellipsoid_mesh({0.635, 0.26, 0.26}, 5, 9, nodes, tets);
  const ShapeTemplate grain = ShapeTemplate::from_mesh("grain", nodes, tets, 20, 0.1);
  EXPECT_TRUE(grain.convex);
  std::vector<Vec3> dented = nodes;
  dented[5] = dented[5] * 0.9;  // a surface node (node 0 is the centre)
  EXPECT_FALSE(ShapeTemplate::from_mesh("dented", dented, tets, 20, 0.05).convex);
  // Two unit corner tetrahedra side by side along x, the second rotated a quarter turn about x:
  // together they are not convex.
  const std::vector<Vec3> l_nodes{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}, {2, 0, 0}, {1, 0, 1}, {1, -1, 0}};
  const std::vector<std::array<int, 4>> l_tets{{0, 1, 2, 3}, {4, 5, 6, 7}};
  const auto l_surface = boundary_triangles(l_nodes, l_tets);
  EXPECT_FALSE(bounds_convex_polytope(l_nodes, l_surface, 2.0 / 6));
  // One tetrahedron is convex; a wrong volume (a surface that does not enclose the mesh) is not.
  const std::vector<std::array<int, 4>> one{{0, 1, 2, 3}};
  const std::vector<Vec3> corner(l_nodes.begin(), l_nodes.begin() + 4);
  EXPECT_TRUE(bounds_convex_polytope(corner, boundary_triangles(corner, one), 1.0 / 6));
  EXPECT_FALSE(bounds_convex_polytope(corner, boundary_triangles(corner, one), 2.0 / 6));
}

}  // namespace
}  // namespace tessera
