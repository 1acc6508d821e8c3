// SPDX-License-Identifier: MIT
#include "solid/triangle_contact.hpp"

#include <cmath>

namespace tessera {

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, TriangleFeature& feature) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  feature = TriangleFeature::vertex;
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  feature = TriangleFeature::edge;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  feature = TriangleFeature::vertex;
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  feature = TriangleFeature::edge;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  feature = TriangleFeature::face;
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

std::vector<TriangleContact> sphere_mesh_contacts(const Vec3& centre, double radius, const std::vector<Vec3>& nodes,
                                                  const std::vector<std::array<int, 3>>& tris,
                                                  const std::vector<int>& candidates) {
  std::vector<TriangleContact> found;
  for (const int t : candidates) {
    TriangleContact c;
    c.triangle = t;
    c.point = closest_point_on_triangle(centre, nodes[tris[t][0]], nodes[tris[t][1]], nodes[tris[t][2]], c.feature);
    const Vec3 d = centre - c.point;
    const double dist = norm(d);
    c.overlap = radius - dist;
    if (c.overlap <= 0 || dist == 0) continue;
    c.normal = d / dist;
    found.push_back(c);
  }
  // A point lies on triangle t when its distance to t is negligible against the sphere's size.
  const double eps2 = 1e-18 * radius * radius;
  auto on_triangle = [&](const Vec3& q, int t) {
    TriangleFeature f;
    const Vec3 x = closest_point_on_triangle(q, nodes[tris[t][0]], nodes[tris[t][1]], nodes[tris[t][2]], f);
    return norm2(x - q) <= eps2;
  };
  std::vector<TriangleContact> kept;
  for (const auto rank : {TriangleFeature::face, TriangleFeature::edge, TriangleFeature::vertex}) {
    const std::size_t before = kept.size();  // contacts of higher priority
    for (const auto& c : found) {
      if (c.feature != rank) continue;
      bool duplicate = false;
      for (std::size_t k = 0; k < kept.size() && !duplicate; ++k)
        duplicate = norm2(kept[k].point - c.point) <= eps2 ||
                    (k < before && c.feature != TriangleFeature::face && on_triangle(c.point, kept[k].triangle));
      if (!duplicate) kept.push_back(c);
    }
  }
  // Back to candidate order, so that the forces are summed in a fixed order.
  std::vector<TriangleContact> ordered;
  for (const int t : candidates)
    for (const auto& c : kept)
      if (c.triangle == t) ordered.push_back(c);
  return ordered;
}

}  // namespace tessera
