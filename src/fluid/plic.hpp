// SPDX-License-Identifier: MIT
// Piecewise-linear interface calculation (PLIC) in one cell (docs/theory.md F5).
//
// In a cell mapped to the unit cube, the interface is the plane n . x = alpha and the liquid is
// the side n . x < alpha (n points out of the liquid). The volume it cuts off is
//   V(n, alpha)
// in closed form (Scardovelli & Zaleski 2000, J. Comput. Phys. 164, 228), and alpha(n, f) is its
// inverse. The liquid volume carried through a face in one direction-split sweep is the part
// of the upwind cell's polyhedron inside the slab swept by the face velocity.
#pragma once

namespace tessera::plic {

// Volume fraction of the unit cube on the side n . x < alpha; any n (a zero normal gives 0 or 1).
double plane_volume(double nx, double ny, double nz, double alpha);

// The alpha for which plane_volume(n, alpha) = f (0 < f < 1, n not zero).
double plane_alpha(double nx, double ny, double nz, double f);

// Liquid volume (as a fraction of the upwind cell's volume) crossing a face normal to direction d
// when the sweep moves a slab of thickness s (0 <= s <= 1, in cell widths) out of the upwind cell:
// out through its high face (high = true: the slab is x_d in [1 - s, 1]) or its low face.
// n, alpha: the upwind cell's interface. Full and empty cells are handled by the caller.
double slab_volume(const double n[3], double alpha, int d, double s, bool high);

}  // namespace tessera::plic
