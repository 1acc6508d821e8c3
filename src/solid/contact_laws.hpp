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
#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

#include "core/vec3.hpp"

namespace tessera {

struct PairParams {
  double normal_stiffness = 0, tangential_stiffness = 0;  // linear law
  double dn_abs = 0, dn_rate = 0, dn_zeta = 0;            // normal damping D_n parts
  double dt_abs = 0, dt_rate = 0, dt_zeta = 0;            // tangential damping D_t parts
  double friction = 0;
  double e_star = 0, g_star = 0, hertz_alpha = 0;  // Hertz-Mindlin
  double restitution = 1;                          // as given or implied (reported)
};

// Per-pair constants of a law, computed once per neighbour-list build (they depend on the pair's
// materials, m* and R* only), so that a contact evaluation needs no table look-up, division or
// square root beyond the geometry's. Each law names its own (Law::Coefficients, five doubles);
// the solver stores any law's in this common slot and the kernel gathers them into lanes.
struct ContactCoefficients {
  static constexpr int count = 5;
  double value[count];
  template <class Law>
  static ContactCoefficients of(const typename Law::Coefficients& c) {
    static_assert(sizeof(typename Law::Coefficients) == sizeof(ContactCoefficients));
    return std::bit_cast<ContactCoefficients>(c);
  }
  template <class Law>
  typename Law::Coefficients as() const {
    return std::bit_cast<typename Law::Coefficients>(*this);
  }
};

// A law (T1-T7) is a type with: `name` (its case-file name), `Coefficients` (five named doubles,
// friction last), `coefficients(PairParams, m*, R*)`, `evaluate(c, delta, v_n, F_n, k_t, D_t)` and
// `contact_duration(PairParams, m*, R*, v)` (T6), `needs_elastic_moduli`. A new law is one more such type here and one
// line in with_law (contact_model.hpp).

// T1, T5.
struct LinearSpringDashpot {
  static constexpr const char* name = "hooke";
  static constexpr bool needs_elastic_moduli = false;  // stiffnesses per material pair
  struct Coefficients {
    double normal_stiffness, normal_damping, tangential_stiffness, tangential_damping, friction;
  };
  static Coefficients coefficients(const PairParams& p, double meff, double /*reff*/) {
    const double dn = p.dn_abs + p.dn_rate * meff + 2.0 * p.dn_zeta * std::sqrt(meff * p.normal_stiffness);
    const double dt = p.dt_abs + p.dt_rate * meff + 2.0 * p.dt_zeta * std::sqrt(meff * p.tangential_stiffness);
    return {p.normal_stiffness, dn, p.tangential_stiffness, dt, p.friction};
  }
  static void evaluate(const Coefficients& c, double delta, double vn, double& fn, double& kt, double& gt) {
    fn = c.normal_stiffness * delta - c.normal_damping * vn;
    kt = c.tangential_stiffness;
    gt = c.tangential_damping;
  }
  // pi / (w0 sqrt(1 - zeta^2)) with the pair's damping ratio at this m* (T6).
  static double contact_duration(const PairParams& p, double meff, double /*reff*/, double /*speed*/) {
    const double w0 = std::sqrt(p.normal_stiffness / meff);
    const double dn = p.dn_abs + p.dn_rate * meff + 2.0 * p.dn_zeta * std::sqrt(meff * p.normal_stiffness);
    const double zeta = dn / (2.0 * std::sqrt(meff * p.normal_stiffness));
    return std::numbers::pi / (w0 * std::sqrt(std::max(1e-12, 1.0 - zeta * zeta)));
  }
};

// T2: F_n = max(0, K delta^(3/2) - D delta^(1/4) v_n), k_t = S delta^(1/2), D_t = G delta^(1/4)
// with K = 4/3 E* sqrt(R*), D = alpha sqrt(m* K), S = 8 G* sqrt(R*), G = alpha sqrt(m* S).
struct HertzMindlin {
  static constexpr const char* name = "hertz_mindlin";
  static constexpr bool needs_elastic_moduli = true;  // E and nu per material
  struct Coefficients {
    double hertz_stiffness, normal_damping_factor, mindlin_stiffness, tangential_damping_factor, friction;
  };
  static Coefficients coefficients(const PairParams& p, double meff, double reff) {
    const double k_hertz = (4.0 / 3.0) * p.e_star * std::sqrt(reff);
    const double k_mindlin = 8.0 * p.g_star * std::sqrt(reff);
    return {k_hertz, p.hertz_alpha * std::sqrt(meff * k_hertz), k_mindlin, p.hertz_alpha * std::sqrt(meff * k_mindlin),
            p.friction};
  }
  static void evaluate(const Coefficients& c, double delta, double vn, double& fn, double& kt, double& gt) {
    const double sd = std::sqrt(delta), qd = std::sqrt(sd);
    fn = std::max(0.0, c.hertz_stiffness * delta * sd - c.normal_damping_factor * qd * vn);
    kt = c.mindlin_stiffness * sd;
    gt = c.tangential_damping_factor * qd;
  }
  // 2.87 (m*^2 / (R* E*^2 v))^(1/5) (T6).
  static double contact_duration(const PairParams& p, double meff, double reff, double speed) {
    return 2.87 * std::pow(meff * meff / (reff * p.e_star * p.e_star * speed), 0.2);
  }
};

// A vector in the plane of plane mode (T15): the in-plane components (u, v) of a 3D one whose
// normal component is zero, for the disc kernel. Its operations are the 3D ones without the zero
// terms: the same values (a term +0 in a sum changes at most the sign of a zero result).
struct PlaneVector {
  double u, v;
  PlaneVector operator+(const PlaneVector& o) const { return {u + o.u, v + o.v}; }
  PlaneVector operator-(const PlaneVector& o) const { return {u - o.u, v - o.v}; }
  PlaneVector operator*(double s) const { return {u * s, v * s}; }
  PlaneVector operator-() const { return {-u, -v}; }
  PlaneVector& operator*=(double s) {
    u *= s, v *= s;
    return *this;
  }
};
inline double dot(const PlaneVector& a, const PlaneVector& b) { return a.u * b.u + a.v * b.v; }
inline double norm2(const PlaneVector& a) { return dot(a, a); }

// Component-wise a where s, b elsewhere (a select, which vectorises).
inline Vec3 pick(bool s, const Vec3& a, const Vec3& b) { return {s ? a.x : b.x, s ? a.y : b.y, s ? a.z : b.z}; }
inline PlaneVector pick(bool s, const PlaneVector& a, const PlaneVector& b) { return {s ? a.u : b.u, s ? a.v : b.v}; }

// Force on body a for one touching contact; updates the tangential spring xi (T3, T4). Written
// without branches (selects only) so that a loop over contacts vectorises; every lane computes
// exactly what a scalar call would, so results do not depend on the vector width. V: Vec3, or
// PlaneVector for discs (the same steps on the in-plane components).
template <class Law, class V>
inline V contact_force(const typename Law::Coefficients& c, double delta, const V& n, const V& v_rel, double dt,
                       V& xi) {
  const double vn = dot(v_rel, n);
  const V vt = v_rel - n * vn;
  double fn = 0, kt = 0, gt = 0;
  Law::evaluate(c, delta, vn, fn, kt, gt);
  // Rotate the spring onto the tangent plane and restore its length: factor sqrt(1 + t),
  // t = xn^2 / |xi_projected|^2. The normal turns little in one step (t ~ (w dt)^2), where the
  // series to t^2 is exact to round-off (error < t^3 / 16).
  const double xn = dot(xi, n);
  const V projected = xi - n * xn;
  const double p2 = norm2(projected);
  const double t = xn * xn / (p2 > 0.0 ? p2 : 1.0);
  const double factor = t < 1e-6 ? 1.0 + t * (0.5 - 0.125 * t) : std::sqrt(1.0 + t);
  xi = projected * factor + vt * dt;
  V ft = -(xi * kt + vt * gt);
  const double limit = c.friction * std::fabs(fn);
  const double ft2 = norm2(ft);
  const bool slide = ft2 > limit * limit;
  const double scale = slide ? limit / std::sqrt(ft2 > 0.0 ? ft2 : 1.0) : 1.0;
  ft *= scale;
  const double inv_kt = kt > 0.0 ? -1.0 / kt : 0.0;
  xi = pick(slide, ft * inv_kt, xi);
  return n * fn + ft;
}

}  // namespace tessera
