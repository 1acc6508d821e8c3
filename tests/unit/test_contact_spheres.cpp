// SPDX-License-Identifier: MIT
// Contact-sphere placement (T12) on the seed's 1.27 x 0.52 mm spheroid: the boundary of the
// tetrahedral mesh is a closed, outward surface; every sphere is tangent to the surface from inside;
// the gap between the surface and the sphere envelope shrinks as spheres are added.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

#include "solid/contact_spheres.hpp"
#include "support/meshes.hpp"

namespace tessera {
namespace {

constexpr double kAx = 0.635e-3, kR = 0.26e-3;

TEST(ContactSpheres, BoundaryIsClosedAndOutward) {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  test::spheroid_fan(kAx, kR, 12, nodes, tets);
  const auto surface = boundary_triangles(nodes, tets);
  EXPECT_EQ(surface.size(), 2u * 24 * 11);
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : surface) {
    const Vec3 n = cross(nodes[t[1]] - nodes[t[0]], nodes[t[2]] - nodes[t[0]]);
    EXPECT_GT(dot(n, (nodes[t[0]] + nodes[t[1]] + nodes[t[2]]) / 3.0), 0.0);  // star-shaped about 0
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  // Consistently oriented closed surface: every directed edge once, its reverse once.
  for (const auto& [e, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({e.second, e.first}), 1u);
  }
}

TEST(ContactSpheres, InsideTangentAndConvergingEnvelope) {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  test::spheroid_fan(kAx, kR, 16, nodes, tets);
  const auto surface = boundary_triangles(nodes, tets);
  // rho below the tips' radius of curvature b^2/a = 106 um, so no sphere pokes out of the smooth
  // surface; against the faceted mesh, whose anchor normals are facet averages, spheres reach a few
  // um past the facets (measured 2.2-3.8 um): bound 5 % of rho.
  const double rho = 0.1e-3;
  double previous = 1e300, first = 0;
  std::printf("  spheres  max gap (um)  overshoot (um)  rms (um)   [rho = %.0f um, body 1270 x 520 um]\n", rho * 1e6);
  for (const int count : {10, 20, 40, 75, 150, 300}) {
    const ContactSpheres cs = place_contact_spheres(nodes, tets, count, rho);
    ASSERT_EQ(cs.centres.size(), static_cast<std::size_t>(count));
    for (const auto& c : cs.centres)  // centres well inside the spheroid
      EXPECT_LT(c.x * c.x / (kAx * kAx) + (c.y * c.y + c.z * c.z) / (kR * kR), 1.0);
    const EnvelopeDeviation e = envelope_deviation(nodes, surface, cs);
    std::printf("  %7d  %12.2f  %14.2f  %8.2f\n", count, e.gap * 1e6, e.overshoot * 1e6, e.rms * 1e6);
    EXPECT_LT(e.overshoot, 0.05 * rho);  // spheres stay inside the surface (to the faceting)
    EXPECT_LE(e.gap, previous);          // more spheres, smaller worst gap
    if (count == 10) first = e.gap;
    previous = e.gap;
  }
  EXPECT_LT(previous, 0.25 * first);
}

}  // namespace
}  // namespace tessera
