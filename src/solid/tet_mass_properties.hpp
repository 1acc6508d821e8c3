// SPDX-License-Identifier: MIT
// Mass properties of a rigid body made of tetrahedra (T10), the T-type model of the drop-impact
// seed: each body's mass and inertia come from its tetrahedra, not from its contact spheres.
//
// For a tetrahedron with vertices a, b, c, d (any orientation), V = |det(b - a, c - a, d - a)| / 6,
// centroid (a + b + c + d) / 4, and the second moments about the origin
//   S_ij = integral x_i x_j dV = V/20 (sum_k v_ki v_kj + (sum_k v_ki)(sum_k v_kj))   (k over vertices),
// which is exact for a linear (uniform-density) tetrahedron (Tonon 2004, J. Math. Stat. 1:8).
// The body's inertia tensor about its centroid is I = rho (tr(S) 1 - S) with S taken about the
// centroid; its eigenvectors are the principal axes (body frame of the rotation integrator, T9).
#pragma once
#include <array>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

struct MassProperties {
  double volume = 0, mass = 0;
  Vec3 centroid;
  std::array<std::array<double, 3>, 3> inertia{};  // about the centroid, in the mesh frame
  Vec3 principal_moments;                          // ascending
  std::array<Vec3, 3> principal_axes;              // unit, right-handed, columns of the rotation
};

// nodes: positions; tets: 4 node indices each. Throws InputError for a degenerate tetrahedron.
MassProperties tet_mass_properties(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 4>>& tets,
                                   double density);

}  // namespace tessera
