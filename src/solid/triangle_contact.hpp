// SPDX-License-Identifier: MIT
// Sphere against a triangle mesh (T11): the closest point of each triangle, classified by the
// feature it lies on (face, edge, vertex; Ericson, Real-Time Collision Detection, 5.1.5), and the
// rule that keeps a contact from being counted twice where triangles meet:
//   1. face contacts are kept, once per point (a centre right above a shared edge projects into both);
//   2. an edge contact is dropped when its point lies on a triangle that has a face contact, or
//      coincides with an edge contact already kept (a ridge seen from both of its triangles);
//   3. a vertex contact is dropped when its point lies on a triangle with a face or edge contact,
//      or coincides with a vertex contact already kept.
// So a sphere rolling across the shared edge of coplanar triangles feels one plane; on a convex
// ridge one contact (at the edge); in a concave valley one contact per face.
#pragma once
#include <array>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

enum class TriangleFeature { face, edge, vertex };

struct TriangleContact {
  int triangle = -1;
  TriangleFeature feature = TriangleFeature::face;
  Vec3 point;      // closest point on the triangle
  Vec3 normal;     // unit, from the triangle to the sphere centre
  double overlap;  // r - |centre - point|
};

// Closest point of triangle (a, b, c) to p, and the feature it lies on.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, TriangleFeature& feature);

// Contacts of a sphere (centre, radius) with the candidate triangles (indices into tris), after
// the de-duplication rule above, in candidate order.
std::vector<TriangleContact> sphere_mesh_contacts(const Vec3& centre, double radius, const std::vector<Vec3>& nodes,
                                                  const std::vector<std::array<int, 3>>& tris,
                                                  const std::vector<int>& candidates);

}  // namespace tessera
