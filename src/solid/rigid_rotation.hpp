// SPDX-License-Identifier: MIT
// Rotation of a rigid body with a general inertia tensor (T9), for bodies made of tetrahedra.
//
// State: orientation q (unit quaternion, body -> world) and angular momentum. Between the torque
// half-kicks of velocity Verlet (L_world += dt/2 T), the body rotates freely; the free rotation
// H = L1^2/(2 I1) + L2^2/(2 I2) + L3^2/(2 I3) (body frame, principal axes) is integrated by the
// symplectic splitting of Dullweber, Leimkuhler & McLachlan (1997, J. Chem. Phys. 107:5840) into
// exact rotations about the body axes, in the symmetric order 1(dt/2) 2(dt/2) 3(dt) 2(dt/2) 1(dt/2).
// Each sub-rotation about axis k by phi = h L_k / I_k turns the body (q <- q (cos phi/2, sin phi/2 e_k))
// and the body-frame momentum (L_body <- R_k(-phi) L_body), so that:
//   - |q| = 1 and the world angular momentum R(q) L_body are preserved to round-off,
//   - the energy error is bounded (no drift), O(dt^2) (second order, time-reversible),
// which tests/verification/test_rigid_rotation.cpp checks, with the intermediate-axis
// (Dzhanibekov) flip period against its analytic value.
#pragma once
#include <cmath>

#include "core/vec3.hpp"

namespace tessera {

struct Quaternion {
  double w = 1, x = 0, y = 0, z = 0;

  Quaternion operator*(const Quaternion& o) const {
    return {w * o.w - x * o.x - y * o.y - z * o.z, w * o.x + x * o.w + y * o.z - z * o.y,
            w * o.y - x * o.z + y * o.w + z * o.x, w * o.z + x * o.y - y * o.x + z * o.w};
  }
  double norm2() const { return w * w + x * x + y * y + z * z; }
  // v in the body frame -> world frame: R(q) v.
  Vec3 rotate(const Vec3& v) const {
    const Vec3 u{x, y, z};
    const Vec3 t = cross(u, v) * 2.0;
    return v + t * w + cross(u, t);
  }
  // World -> body: R(q)^T v.
  Vec3 unrotate(const Vec3& v) const { return Quaternion{w, -x, -y, -z}.rotate(v); }
};

// The unit quaternion of a rotation matrix given by its columns (body axes in the world frame,
// right-handed, orthonormal): Shepperd's method (largest diagonal term first, stable for any angle).
inline Quaternion quaternion_from_axes(const Vec3& c0, const Vec3& c1, const Vec3& c2) {
  const double m00 = c0.x, m10 = c0.y, m20 = c0.z, m01 = c1.x, m11 = c1.y, m21 = c1.z, m02 = c2.x, m12 = c2.y,
               m22 = c2.z;
  const double tr = m00 + m11 + m22;
  Quaternion q;
  if (tr >= m00 && tr >= m11 && tr >= m22) {
    const double s = 2 * std::sqrt(1 + tr);
    q = {0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s};
  } else if (m00 >= m11 && m00 >= m22) {
    const double s = 2 * std::sqrt(1 + m00 - m11 - m22);
    q = {(m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s};
  } else if (m11 >= m22) {
    const double s = 2 * std::sqrt(1 + m11 - m00 - m22);
    q = {(m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s};
  } else {
    const double s = 2 * std::sqrt(1 + m22 - m00 - m11);
    q = {(m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s};
  }
  const double n = std::sqrt(q.norm2());
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}

// sin and cos; for |phi| < 1e-2 (every DEM step: w dt is ~1e-4) by their Taylor series, whose
// truncation error (phi^10 / 10! < 3e-27) lies far below round-off, in Horner form with the
// reciprocal factorial ratios as constants (multiplications: a division chain cost as much as the
// rest of a rotation step); otherwise libm's.
inline void small_angle_sincos(double phi, double& s, double& c) {
  if (std::fabs(phi) < 1e-2) {
    constexpr double k6 = 1.0 / 6, k20 = 1.0 / 20, k42 = 1.0 / 42, k72 = 1.0 / 72;
    constexpr double k2 = 0.5, k12 = 1.0 / 12, k30 = 1.0 / 30, k56 = 1.0 / 56, k90 = 1.0 / 90;
    const double p2 = phi * phi;
    s = phi * (1 - p2 * k6 * (1 - p2 * k20 * (1 - p2 * k42 * (1 - p2 * k72))));
    c = 1 - p2 * k2 * (1 - p2 * k12 * (1 - p2 * k30 * (1 - p2 * k56 * (1 - p2 * k90))));
  } else {
    s = std::sin(phi);
    c = std::cos(phi);
  }
}

// Free rotation over dt; L_body is the angular momentum in the body (principal) frame, inertia the
// principal moments. For W bodies at once: the same operations on each, in the same order (the same
// bits as one at a time), interleaved so that the bodies' chains of dependent operations overlap.
template <int W>
inline void free_rotation_steps(Quaternion* q, Vec3* L_body, const Vec3* inertia, const double* dt) {
  auto sub = [&](int k, double f) {
    double sh[W], ch[W], half[W];
    for (int b = 0; b < W; ++b) half[b] = 0.5 * ((f * dt[b]) * L_body[b][k] / inertia[b][k]);
    // The series for all, then libm's for any angle beyond it (small_angle_sincos, branch-free here).
    for (int b = 0; b < W; ++b) {
      constexpr double k6 = 1.0 / 6, k20 = 1.0 / 20, k42 = 1.0 / 42, k72 = 1.0 / 72;
      constexpr double k2 = 0.5, k12 = 1.0 / 12, k30 = 1.0 / 30, k56 = 1.0 / 56, k90 = 1.0 / 90;
      const double p = half[b], p2 = p * p;
      sh[b] = p * (1 - p2 * k6 * (1 - p2 * k20 * (1 - p2 * k42 * (1 - p2 * k72))));
      ch[b] = 1 - p2 * k2 * (1 - p2 * k12 * (1 - p2 * k30 * (1 - p2 * k56 * (1 - p2 * k90))));
    }
    for (int b = 0; b < W; ++b)
      if (!(std::fabs(half[b]) < 1e-2)) small_angle_sincos(half[b], sh[b], ch[b]);
    const int a = (k + 1) % 3, c2 = (k + 2) % 3;
    for (int b = 0; b < W; ++b) {
      // The half angle's sine and cosine turn q; the whole angle's follow from them by the
      // double-angle formulas (one series per sub-rotation instead of two).
      const double s = 2 * sh[b] * ch[b], c = 1 - 2 * sh[b] * sh[b];
      // L_body <- R_k(-phi) L_body: rotate the (a, c2) components by -phi.
      const double la = L_body[b][a], lb = L_body[b][c2];
      L_body[b][a] = c * la + s * lb;
      L_body[b][c2] = -s * la + c * lb;
      Quaternion r{ch[b], 0, 0, 0};
      (k == 0 ? r.x : (k == 1 ? r.y : r.z)) = sh[b];
      q[b] = q[b] * r;
    }
  };
  sub(0, 0.5);
  sub(1, 0.5);
  sub(2, 1.0);
  sub(1, 0.5);
  sub(0, 0.5);
  // Products of unit quaternions drift from |q| = 1 only by round-off; one Newton step removes it.
  for (int b = 0; b < W; ++b) {
    const double scale = 0.5 * (3.0 - q[b].norm2());
    q[b].w *= scale, q[b].x *= scale, q[b].y *= scale, q[b].z *= scale;
  }
}

inline void free_rotation_step(Quaternion& q, Vec3& L_body, const Vec3& inertia, double dt) {
  free_rotation_steps<1>(&q, &L_body, &inertia, &dt);
}

}  // namespace tessera
