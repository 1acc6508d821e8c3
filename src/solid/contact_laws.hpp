// SPDX-License-Identifier: MIT
// Contact laws between two contact spheres, or a contact sphere and a wall (the same code serves
// both, so walls cannot drift from particles). Equations numbered as in docs/theory.md.
//
// Geometry: n is the unit normal pointing from body b to body a, delta > 0 the overlap, and
// v_rel = (v_a + w_a x (-R_a n)) - (v_b + w_b x (R_b n)) the relative velocity at the contact,
// split into v_n = (v_rel . n) n and v_t = v_rel - v_n. m* = m_a m_b / (m_a + m_b),
// R* = R_a R_b / (R_a + R_b) (a wall: m_b, R_b -> infinity).
//
// Normal force on a (T1 linear, T2 Hertz), drop-impact seed eq. (4):
//   F_n = (k_n delta - D_n v_n) n                                              (T1)
//   F_n = max(0, K delta^(3/2) - alpha sqrt(m* K) delta^(1/4) v_n) n,
//         K = 4/3 E* sqrt(R*)                                                  (T2)
// Tangential force, seed eqs. (5)-(6), with the spring history xi (accumulated while in contact,
// rotated onto the current tangent plane keeping its length, cleared on separation):
//   xi <- xi + v_t dt,   F_t = -k_t xi - D_t v_t                                (T3)
//   if |F_t| > mu |F_n|:  F_t <- mu |F_n| F_t / |F_t|,  xi <- -F_t / k_t        (T4)
// (T4) caps the spring at the friction limit; in steady sliding F_t / |F_t| = -v_t / |v_t|, the
// direction of eq. (6). Hertz-Mindlin uses k_t = 8 G* sqrt(R* delta) and D_t = alpha sqrt(m* k_t).
// Damping: D = D_abs + D_rate m* + 2 zeta sqrt(m* k), which covers the seed's absolute D (N s/m),
// LAMMPS' rate form (gamma m*, 1/s) and a restitution coefficient (zeta, T5).
#pragma once
#include <cmath>

#include "core/vec3.hpp"

namespace tessera {

struct PairParams {
  double normal_stiffness = 0, tangential_stiffness = 0;  // linear law
  double dn_abs = 0, dn_rate = 0, dn_zeta = 0;             // normal damping D_n parts
  double dt_abs = 0, dt_rate = 0, dt_zeta = 0;             // tangential damping D_t parts
  double friction = 0;
  double e_star = 0, g_star = 0, hertz_alpha = 0;          // Hertz-Mindlin
  double restitution = 1;                                   // as given or implied (reported)
};

struct LinearSpringDashpot {
  static constexpr const char* name = "hooke";
  static void evaluate(const PairParams& p, double delta, double vn, double meff, double /*reff*/,
                       double& fn, double& kt, double& gt) {
    const double dn = p.dn_abs + p.dn_rate * meff + 2.0 * p.dn_zeta * std::sqrt(meff * p.normal_stiffness);
    fn = p.normal_stiffness * delta - dn * vn;
    kt = p.tangential_stiffness;
    gt = p.dt_abs + p.dt_rate * meff + 2.0 * p.dt_zeta * std::sqrt(meff * p.tangential_stiffness);
  }
};

struct HertzMindlin {
  static constexpr const char* name = "hertz_mindlin";
  static void evaluate(const PairParams& p, double delta, double vn, double meff, double reff,
                       double& fn, double& kt, double& gt) {
    const double sqrt_rd = std::sqrt(reff * delta);
    const double k_hertz = (4.0 / 3.0) * p.e_star * std::sqrt(reff);
    const double damping = p.hertz_alpha * std::sqrt(meff * k_hertz) * std::sqrt(std::sqrt(delta));
    fn = std::max(0.0, k_hertz * delta * std::sqrt(delta) - damping * vn);
    kt = 8.0 * p.g_star * sqrt_rd;
    gt = p.hertz_alpha * std::sqrt(meff * kt);
  }
};

// Force on body a for one touching contact; updates the tangential history in place (T3, T4).
template <class Law>
inline Vec3 contact_force(const PairParams& p, double delta, const Vec3& n, const Vec3& v_rel,
                          double meff, double reff, double dt, double* history) {
  const double vn = dot(v_rel, n);
  const Vec3 vt = v_rel - n * vn;
  double fn = 0, kt = 0, gt = 0;
  Law::evaluate(p, delta, vn, meff, reff, fn, kt, gt);

  Vec3 xi = Vec3::load(history);
  const double xi2 = norm2(xi);
  if (xi2 > 0.0) {
    xi -= n * dot(xi, n);
    const double projected2 = norm2(xi);
    if (projected2 > 0.0) xi *= std::sqrt(xi2 / projected2);
  }
  xi += vt * dt;
  Vec3 ft = -(xi * kt + vt * gt);
  const double limit = p.friction * std::fabs(fn);
  const double ft2 = norm2(ft);
  if (ft2 > limit * limit) {
    ft *= limit / std::sqrt(ft2);
    xi = kt > 0.0 ? ft * (-1.0 / kt) : Vec3{};
  }
  xi.store(history);
  return n * fn + ft;
}

}  // namespace tessera
