// SPDX-License-Identifier: MIT
// The contact kernel's mirrors of the body arrays, packed each step so that a contact touches a few
// cache lines per partner instead of 7-8 scattered arrays, and the per-body force slots the contacts
// accumulate into (DemSolver::compute_forces).
//
// 3D (spheres, and shaped bodies' elements): geometry (half a line), motion (a line), force (a line).
// Plane mode (T15): a disc moves in two axes (u < v, the normal's others) and turns about the
// normal, so its mirror (in-plane centre, radius, in-plane velocity, spin) fills one line and its
// force slot (in-plane force, torque about the normal) half of one. The components the 3D mirrors
// would carry along the normal are zero (positions: the plane's coordinate, the same for every disc):
// the disc kernel writes those zeros into the lanes, and the other results keep their bits.
#pragma once

namespace tessera {

struct alignas(32) KernelGeometry {
  double x, y, z, r;
};
struct alignas(64) KernelMotion {
  double vx, vy, vz, wx, wy, wz;
};
struct alignas(64) KernelForce {
  double fx, fy, fz, tx, ty, tz;
};

struct alignas(64) DiscMirror {
  double u, v, r, vu, vv, wn;
};
struct alignas(32) DiscForce {
  double fu, fv, tn;
};

// The in-plane axes of a plane normal to axis n: u < v.
constexpr int plane_u(int n) { return n == 0 ? 1 : 0; }
constexpr int plane_v(int n) { return n == 2 ? 1 : 2; }

}  // namespace tessera
