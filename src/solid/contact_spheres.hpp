// SPDX-License-Identifier: MIT
// Contact spheres of a body made of tetrahedra (T12): the T-type model detects contacts with spheres
// placed inside the body near its surface, so that the body collides like its surface.
//
// Placement (deterministic): the boundary triangles are the tetrahedron faces that appear once; the
// surface nodes get outward normals (area-weighted means of their triangles' normals), the triangle
// centroids their face normals; N anchors are chosen by farthest-point sampling over these candidates
// (start: the surface node farthest from the centroid of the surface nodes); each anchor s with
// normal n carries a sphere of radius rho centred at s - rho n, tangent
// to the surface at s from inside.
// Envelope deviation: for surface points p (nodes and triangle centroids), the gap between the
// surface and the union of spheres, d(p) = min_i (|p - c_i| - rho): > 0 the surface is not covered
// there, < 0 a sphere pokes out of the surface. rho must stay below the surface's smallest radius
// of curvature (a prolate spheroid's tips: b^2/a) or spheres poke out near the anchors.
#pragma once
#include <array>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

struct ContactSpheres {
  std::vector<Vec3> centres;  // in the mesh frame
  double radius = 0;
};

// Boundary triangles of a tetrahedral mesh, oriented with outward normals.
std::vector<std::array<int, 3>> boundary_triangles(const std::vector<Vec3>& nodes,
                                                   const std::vector<std::array<int, 4>>& tets);

// count spheres of the given radius (count <= surface nodes + surface triangles).
ContactSpheres place_contact_spheres(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 4>>& tets,
                                     int count, double radius);

struct EnvelopeDeviation {
  double gap = 0;        // max of d(p): the largest uncovered depth
  double overshoot = 0;  // max of -d(p): the farthest a sphere reaches outside the surface
  double rms = 0;        // of d(p)
};
EnvelopeDeviation envelope_deviation(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 3>>& surface,
                                     const ContactSpheres& spheres);

}  // namespace tessera
