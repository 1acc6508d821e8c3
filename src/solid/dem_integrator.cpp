// SPDX-License-Identifier: MIT
// Velocity Verlet for the DEM's bodies (T8; shaped bodies: the DLM splitting of T9; discs: T15):
// the first half-kick and drift with the mirrors of the contact kernel packed in the same pass,
// the second half-kick (deferred into the next first pass when the run loop allows it), the
// external loads (the fluid force, a borehole's pressure), set_dt and advance(dt, substeps).
#include <algorithm>
#include <cmath>
#include <string>

#include "core/errors.hpp"
#include "solid/dem_solver.hpp"

namespace tessera {

void DemSolver::integrate_first() {
  // External loads and the kind of body (a disc's normal too) are compile-time choices: scenes
  // without loads run the loop they always ran, and a disc's axes are constants in its loop.
  const Bodies kind = shaped()       ? Bodies::shaped
                      : plane_mode() ? static_cast<Bodies>(static_cast<int>(Bodies::discs_x) + plane_normal())
                                     : Bodies::spheres;
  auto run = [&]<bool kExternal>() {
    switch (kind) {
      case Bodies::shaped: return integrate_first_impl<Bodies::shaped, kExternal>();
      case Bodies::spheres: return integrate_first_impl<Bodies::spheres, kExternal>();
      case Bodies::discs_x: return integrate_first_impl<Bodies::discs_x, kExternal>();
      case Bodies::discs_y: return integrate_first_impl<Bodies::discs_y, kExternal>();
      case Bodies::discs_z: return integrate_first_impl<Bodies::discs_z, kExternal>();
    }
  };
  if (external_loads_)
    run.template operator()<true>();
  else
    run.template operator()<false>();
}

void DemSolver::integrate_second() {
  if (external_loads_)
    integrate_second_impl<true>();
  else
    integrate_second_impl<false>();
}

void DemSolver::use_external_loads(bool on) {
  apply_pending_kick();  // the pending half-kick belongs to the loads it was computed with
  external_loads_ = on;
}

void DemSolver::set_dt(double dt) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw RunError("DemSolver::set_dt: the time step must be positive and finite, not " + std::to_string(dt));
  apply_pending_kick();  // its half-kick is dt/2 of the old step
  dt_ = dt;
}

void DemSolver::set_gravity(const Vec3& g) {
  apply_pending_kick();  // its half-kick saw the old gravity
  settings_.gravity = g;
}

void DemSolver::advance(double dt, int substeps) {
  if (substeps < 1) throw RunError("DemSolver::advance: at least one sub-step, not " + std::to_string(substeps));
  if (dt != dt_) set_dt(dt);
  // Each sub-step but the last defers its second half-kick into the next one's first pass (the
  // same bits as two passes, one sweep fewer); the last one leaves full-step velocities.
  for (int k = 0; k < substeps; ++k) step(k + 1 < substeps);
  complete_step();
}

void DemSolver::fold_turns() {
  // q <- (cos phi/2, sin phi/2 n) q: the rotation by the turn phi about the plane's normal n, in
  // the world frame as T8's update (rotations about one axis commute, so the sum of the steps'
  // turns is exact).
  if (!plane_mode()) return;
  const int normal = plane_normal();
  for (std::size_t i = 0; i < turn_.size() && i < p_.owned; ++i) {
    if (turn_[i] == 0.0) continue;
    const double s = std::sin(0.5 * turn_[i]), c = std::cos(0.5 * turn_[i]);
    Quaternion r{c, 0, 0, 0};
    (normal == 0 ? r.x : (normal == 1 ? r.y : r.z)) = s;
    const Quaternion q = r * Quaternion{p_.q[4 * i], p_.q[4 * i + 1], p_.q[4 * i + 2], p_.q[4 * i + 3]};
    const double scale = 0.5 * (3.0 - q.norm2());
    p_.q[4 * i] = q.w * scale, p_.q[4 * i + 1] = q.x * scale, p_.q[4 * i + 2] = q.y * scale,
             p_.q[4 * i + 3] = q.z * scale;
    turn_[i] = 0.0;
  }
}

// Orientation: q <- normalize(q + dt/2 (0, w) q). The update changes |q|^2 by O((w dt)^2), so one
// Newton step of 1/sqrt about 1 normalises to round-off without a square root.
static inline void turn_sphere(double* __restrict qi, const double* wi, double h) {
  const double qw = qi[0], qx = qi[1], qy = qi[2], qz = qi[3];
  const double a = qw + h * (-wi[0] * qx - wi[1] * qy - wi[2] * qz);
  const double b = qx + h * (wi[0] * qw + wi[1] * qz - wi[2] * qy);
  const double c = qy + h * (wi[1] * qw + wi[2] * qx - wi[0] * qz);
  const double d = qz + h * (wi[2] * qw + wi[0] * qy - wi[1] * qx);
  const double scale = 0.5 * (3.0 - (a * a + b * b + c * c + d * d));
  qi[0] = a * scale, qi[1] = b * scale, qi[2] = c * scale, qi[3] = d * scale;
}

template <DemSolver::Bodies kBodies, bool kExternal>
void DemSolver::integrate_first_impl() {
  constexpr bool kSpheres = kBodies != Bodies::shaped;
  const double h = 0.5 * dt_, dt = dt_;
  const double g[3] = {settings_.gravity.x, settings_.gravity.y, settings_.gravity.z};
  double* __restrict x = p_.x.data();
  double* __restrict v = p_.v.data();
  double* __restrict w = p_.omega.data();
  double* __restrict q = p_.q.data();
  const double* __restrict f = p_.f.data();
  const double* __restrict t = p_.torque.data();
  const double* __restrict fe = p_.f_ext.data();
  const double* __restrict te = p_.t_ext.data();
  const double* __restrict inv_m = inv_mass_.data();
  const double* __restrict inv_i = inv_inertia_.data();
  const std::size_t n = p_.owned;
  const double* vmask = velocity_mask_.data();  // all ones in 3D; plane mode zeroes the normal
  const double* wmask = spin_mask_.data();      // components (multiplying by 1 keeps every bit)
  // Sphere bodies, in the same pass (from registers): the contact kernel's mirrors of the owned
  // bodies (a rebuild reorders the bodies and repacks everything), the orientation, and the
  // largest displacements since the list build and the moving walls' search (needs_rebuild).
  // Discs (plane mode) turn about the normal only: the step adds dt w_n to their turn, which
  // fold_turns applies to q at the next rebuild or output (a 2D orientation is one angle).
  double* __restrict turn = turn_.data();
  constexpr bool kDiscs = kBodies >= Bodies::discs_x;
  constexpr int normal = kDiscs ? static_cast<int>(kBodies) - static_cast<int>(Bodies::discs_x) : 0;
  constexpr int plane_a = plane_u(normal), plane_b = plane_v(normal);
  auto& geometry_mirrors = entities_.geometry_mirrors();
  auto& motion_mirrors = entities_.motion_mirrors();
  auto& disc_mirrors = entities_.disc_mirrors();
  owned_mirrors_current_ = kDiscs ? disc_mirrors.size() >= n
                                  : kSpheres && geometry_mirrors.size() >= n && motion_mirrors.size() >= n;
  KernelGeometry* __restrict kg = geometry_mirrors.data();
  KernelMotion* __restrict km = motion_mirrors.data();
  DiscMirror* __restrict kdm = disc_mirrors.data();
  const double* x0 = x_build_.data();
  const double* xm = x_moving_build_.data();
  double moved2 = 0, moved_since_walls2 = 0;
  // A deferred second half-kick (step(true)) comes first, with the forces from the contact buffer.
  const bool both = kSpheres && kick_pending_;
  kick_pending_ = false;
  const KernelForce* __restrict kf = entities_.forces().data();
  const DiscForce* __restrict kd = entities_.disc_forces().data();
  if constexpr (kDiscs) {
    // Discs: only the in-plane components move (the normal's velocity and the in-plane spin stay
    // zero, the position along the normal stays put). The same operations on those components as
    // the 3D loop below, without its masks (a product by 1) and zero terms (a sum with +0): the
    // same bits.
    constexpr int A = plane_a, B = plane_b, N = normal;
    for (std::size_t i = 0; i < n; ++i) {
      const double a = inv_m[i], b = inv_i[i];  // loads before stores (4K aliasing: see below)
      double va = v[3 * i + A], vb = v[3 * i + B], wn = w[3 * i + N];
      double fa, fb, tn;
      if (both) {
        fa = kd[i].fu, fb = kd[i].fv, tn = kd[i].tn;
        if constexpr (kExternal) fa += fe[3 * i + A], fb += fe[3 * i + B], tn += te[3 * i + N];
        va = va + h * (fa * a + g[A]), vb = vb + h * (fb * a + g[B]), wn = wn + h * tn * b;
      } else {
        fa = f[3 * i + A], fb = f[3 * i + B], tn = t[3 * i + N];
        if constexpr (kExternal) fa += fe[3 * i + A], fb += fe[3 * i + B], tn += te[3 * i + N];
      }
      va = va + h * (fa * a + g[A]), vb = vb + h * (fb * a + g[B]), wn = wn + h * tn * b;
      const double xa = x[3 * i + A] + dt * va, xb = x[3 * i + B] + dt * vb;
      const double da = xa - x0[3 * i + A], db = xb - x0[3 * i + B];
      const double ma = xa - xm[3 * i + A], mb = xb - xm[3 * i + B];
      v[3 * i + A] = va, v[3 * i + B] = vb, w[3 * i + N] = wn, x[3 * i + A] = xa, x[3 * i + B] = xb;
      if (owned_mirrors_current_) kdm[i] = {xa, xb, p_.radius[i], va, vb, wn};
      turn[i] += dt * wn;
      moved2 = std::max(moved2, da * da + db * db);
      moved_since_walls2 = std::max(moved_since_walls2, ma * ma + mb * mb);
    }
    moved2_[0] = moved2, moved2_[1] = moved_since_walls2;
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    // The body arrays are page-aligned allocations of equal size: a store to v[j] followed by a
    // load of x[j] would stall (4K aliasing). Load a body's values first, then store.
    const double a = inv_m[i], b = inv_i[i];
    double vi[3], wi[3], xi[3], fi[3], ti[3];
    for (int k = 0; k < 3; ++k) vi[k] = v[3 * i + k], wi[k] = w[3 * i + k];
    if (both) {
      if constexpr (kDiscs) {
        fi[0] = fi[1] = fi[2] = ti[0] = ti[1] = ti[2] = 0.0;
        fi[plane_a] = kd[i].fu, fi[plane_b] = kd[i].fv, ti[normal] = kd[i].tn;
      } else {
        fi[0] = kf[i].fx, fi[1] = kf[i].fy, fi[2] = kf[i].fz, ti[0] = kf[i].tx, ti[1] = kf[i].ty, ti[2] = kf[i].tz;
      }
      if constexpr (kExternal)
        for (int k = 0; k < 3; ++k) fi[k] += fe[3 * i + k], ti[k] += te[3 * i + k];
      for (int k = 0; k < 3; ++k) {
        vi[k] = (vi[k] + h * (fi[k] * a + g[k])) * vmask[k];
        wi[k] = (wi[k] + h * ti[k] * b) * wmask[k];
      }
    } else {
      for (int k = 0; k < 3; ++k) fi[k] = f[3 * i + k], ti[k] = t[3 * i + k];
      if constexpr (kExternal)
        for (int k = 0; k < 3; ++k) fi[k] += fe[3 * i + k], ti[k] += te[3 * i + k];
    }
    for (int k = 0; k < 3; ++k) {
      vi[k] = (vi[k] + h * (fi[k] * a + g[k])) * vmask[k];
      wi[k] = (wi[k] + h * ti[k] * b) * wmask[k];
      xi[k] = x[3 * i + k] + dt * vi[k];
    }
    for (int k = 0; k < 3; ++k) v[3 * i + k] = vi[k], w[3 * i + k] = wi[k], x[3 * i + k] = xi[k];
    if constexpr (kSpheres) {
      if (owned_mirrors_current_) {
        if constexpr (kDiscs) {
          kdm[i] = {xi[plane_a], xi[plane_b], p_.radius[i], vi[plane_a], vi[plane_b], wi[normal]};
        } else {
          kg[i] = {xi[0], xi[1], xi[2], p_.radius[i]};
          km[i] = {vi[0], vi[1], vi[2], wi[0], wi[1], wi[2]};
        }
      }
      if constexpr (kDiscs)
        turn[i] += dt * wi[normal];
      else
        turn_sphere(q + 4 * i, wi, h);
      const double dx = xi[0] - x0[3 * i], dy = xi[1] - x0[3 * i + 1], dz = xi[2] - x0[3 * i + 2];
      const double mx = xi[0] - xm[3 * i], my = xi[1] - xm[3 * i + 1], mz = xi[2] - xm[3 * i + 2];
      moved2 = std::max(moved2, dx * dx + dy * dy + dz * dz);
      moved_since_walls2 = std::max(moved_since_walls2, mx * mx + my * my + mz * mz);
    }
  }
  if constexpr (kSpheres) {
    moved2_[0] = moved2, moved2_[1] = moved_since_walls2;
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      if (anisotropic(p_.shape[i])) {
        if constexpr (kExternal) {
          const double total[3] = {t[3 * i] + te[3 * i], t[3 * i + 1] + te[3 * i + 1], t[3 * i + 2] + te[3 * i + 2]};
          rotate_shaped(i, total, h, dt);
        } else {
          rotate_shaped(i, t + 3 * i, h, dt);
        }
      } else {
        turn_sphere(q + 4 * i, w + 3 * i, h);
      }
    }
  }
}

template <bool kExternal>
void DemSolver::integrate_second_impl() {
  // Takes the new forces from the contact buffer (one pass: store F, T and kick). The stored F, T
  // are the contacts' alone: the next first half-kick adds the external load again.
  const double h = 0.5 * dt_;
  const double g[3] = {settings_.gravity.x, settings_.gravity.y, settings_.gravity.z};
  double* __restrict v = p_.v.data();
  double* __restrict w = p_.omega.data();
  double* __restrict f = p_.f.data();
  double* __restrict t = p_.torque.data();

  const double* __restrict fe = p_.f_ext.data();
  const double* __restrict te = p_.t_ext.data();
  const double* __restrict inv_m = inv_mass_.data();
  const double* __restrict inv_i = inv_inertia_.data();
  const std::size_t n = p_.owned;
  const double* vmask = velocity_mask_.data();
  const double* wmask = spin_mask_.data();
  for (std::size_t i = 0; i < n; ++i) {
    const KernelForce in = entities_.load(i);
    const double fi[3] = {in.fx, in.fy, in.fz}, ti[3] = {in.tx, in.ty, in.tz};
    double fa[3] = {fi[0], fi[1], fi[2]}, ta[3] = {ti[0], ti[1], ti[2]};  // what accelerates the body
    if constexpr (kExternal)
      for (int k = 0; k < 3; ++k) fa[k] += fe[3 * i + k], ta[k] += te[3 * i + k];
    double vi[3], wi[3];  // loads before stores (see integrate_first)
    for (int k = 0; k < 3; ++k) {
      vi[k] = (v[3 * i + k] + h * (fa[k] * inv_m[i] + g[k])) * vmask[k];
      wi[k] = (w[3 * i + k] + h * ta[k] * inv_i[i]) * wmask[k];
    }
    for (int k = 0; k < 3; ++k) f[3 * i + k] = fi[k], t[3 * i + k] = ti[k], v[3 * i + k] = vi[k], w[3 * i + k] = wi[k];
  }
  if (shaped())
    for (std::size_t i = 0; i < n; ++i) {
      if (!anisotropic(p_.shape[i])) continue;
      double total[3] = {t[3 * i], t[3 * i + 1], t[3 * i + 2]};
      if constexpr (kExternal)
        for (int k = 0; k < 3; ++k) total[k] += te[3 * i + k];
      rotate_shaped(i, total, h, 0.0);
    }
}

void DemSolver::rotate_shaped(std::size_t i, const double* torque, double h, double dt) {
  // Half-kick of the angular momentum by the torque (in the body frame: L_b = I R^T w,
  // L_b += dt/2 R^T T), then (dt > 0) the free rotation over dt (T9), then w = R I^-1 L_b.
  Quaternion q{p_.q[4 * i], p_.q[4 * i + 1], p_.q[4 * i + 2], p_.q[4 * i + 3]};
  const Vec3 inertia = Vec3::load(&inertia3_[3 * i]);
  const Vec3 wb = q.unrotate(p_.ang(i));
  Vec3 lb{inertia.x * wb.x, inertia.y * wb.y, inertia.z * wb.z};
  lb += q.unrotate(Vec3::load(torque) * h);
  if (dt > 0) free_rotation_step(q, lb, inertia, dt);
  const Vec3 w = q.rotate({lb.x / inertia.x, lb.y / inertia.y, lb.z / inertia.z});
  for (int k = 0; k < 3; ++k) p_.omega[3 * i + k] = w[k];
  p_.q[4 * i] = q.w, p_.q[4 * i + 1] = q.x, p_.q[4 * i + 2] = q.y, p_.q[4 * i + 3] = q.z;
}

void DemSolver::kick_free_spheres(bool drift) {
  // Half-kick (and, after the first, the drift) of velocity Verlet, masked as the grains' are.
  const double h = 0.5 * dt_;
  const Vec3 vmask{velocity_mask_[0], velocity_mask_[1], velocity_mask_[2]};
  const Vec3 wmask{spin_mask_[0], spin_mask_[1], spin_mask_[2]};
  for (auto& s : free_.spheres()) {
    s.v = hadamard(s.v + (s.force / s.mass + settings_.gravity) * h, vmask);
    s.omega = hadamard(s.omega + s.torque * (h / s.inertia), wmask);
    if (drift) s.x += s.v * dt_;
  }
}

void DemSolver::kick_pivots(bool second) {
  // A pivot mesh's angle (T14): theta' += dt/2 theta'' in both halves; the second half first takes
  // theta'' from the step's loads.
  for (auto& m : walls_.meshes()) {
    if (second) m.update_acceleration(settings_.gravity);
    if (m.motion != MeshWall::Motion::pivot) continue;
    m.theta_dot += 0.5 * dt_ * m.theta_ddot;
    if (second) m.omega = m.axis * m.theta_dot;
  }
}

void DemSolver::apply_pending_kick() {
  if (!kick_pending_) return;
  auto t = timers_.scope("integrate");
  integrate_second();
  kick_pending_ = false;
}

void DemSolver::complete_step() {
  apply_pending_kick();
  fold_turns();
}

}  // namespace tessera
