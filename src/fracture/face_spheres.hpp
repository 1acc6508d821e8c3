// SPDX-License-Identifier: MIT
// Contact spheres on a broken face (blast seed 2.2, Fig. 5; docs/theory.md B6): each edge of the
// face is divided into `divisions` equal parts; a sphere touches the face from inside the element at
// every interior crossing of the division lines (barycentric (i, j, k) / divisions, i, j, k >= 1:
// 6 points for 5 divisions), as large as the element allows: its centre p - r n (n the face's
// outward normal) is at least r from each of the other three face planes,
//   r = min_g (p - a_g) . m_g / (1 + n . m_g)   (m_g the inward normal of face g, a_g a point on it).
// The spheres of the two faces of a broken bond touch at zero overlap, point for point.
#pragma once
#include <array>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

struct FaceSphere {
  Vec3 centre;  // body frame
  double radius = 0;
};

// Spheres on local face `face` (the one opposite vertex `face`) of the tetrahedron `v`.
std::vector<FaceSphere> face_spheres(const std::array<Vec3, 4>& v, int face, int divisions);

}  // namespace tessera
