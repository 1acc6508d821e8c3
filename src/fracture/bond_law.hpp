// SPDX-License-Identifier: MIT
// The pre-fracture bond of the blast seed (section 2.1, Figs. 1-4; docs/theory.md B2-B4): two
// tetrahedra that share a face are joined at its three vertices, each vertex carrying a third of the
// face's area A. At a vertex, u is the slave's point minus the master's point (world), split in the
// master face's frame into the opening u_n = u . n (n: the master's outward normal; tension > 0)
// and the tangential u_t = (u . xi, u . eta).
//
//   B2 stresses per unit area: sigma(u_n) below, tau = k_s |d|, d = u_t - u_0;
//      force on the slave  F = -(A/3) [(sigma + c_n du_n/dt) n + k_s d + c_s du_t/dt], on the master -F.
//   B3 shear (Coulomb, eqs. 1-2): when k_s |d| > tau_max = max(0, c - sigma tan(phi)) (sigma
//      tension-positive, so compression raises the limit), the slip grows
//      u_0 <- u_0 + (|d| - tau_max / k_s) d / |d|, and tau = tau_max.
//   B4 normal (Fig. 4): compression k_n u_n without limit; tension elastic up to u_E = sigma_f / k_n,
//      then linear softening sigma = sigma_f - k_f (u_n - u_E) down to zero at u_f; unloading and
//      reloading run on the line from the origin to the point (u_m, sigma(u_m)) where unloading
//      began, u_m being the largest opening reached (the elastic limit "moved to the unload point").
//      The area under the envelope is the energy a unit of face dissipates when it breaks:
//      G_f = sigma_f u_f / 2, so u_f = 2 G_f / sigma_f and k_f = sigma_f / (u_f - u_E); this needs
//      u_f > u_E, i.e. sigma_f < sqrt(2 G_f k_n) (9.47 MPa with the seed's G_f and k_n).
//   B5 failure: a vertex fails when u_n >= u_f; the whole face is then released (section 2.1).
#pragma once
#include <algorithm>
#include <cmath>

namespace tessera {

struct BondLaw {
  double kn = 450e9, ks = 90e9;     // springs per unit area, N/m^3 (Table 1)
  double cn = 22.6e6, cs = 10.1e6;  // dashpots per unit area, N s/m^3
  double cohesion = 6.66e6;         // c, Pa
  double friction = 0.58;           // tan(phi)
  double tensile_strength = 2.43e6;  // sigma_f, Pa (not in Table 1; docs/theory.md B4)
  double fracture_energy = 99.67;   // G_f, N/m

  double u_elastic() const { return tensile_strength / kn; }
  double u_failure() const { return 2 * fracture_energy / tensile_strength; }
  double softening() const { return tensile_strength / (u_failure() - u_elastic()); }
  // sigma_f < sqrt(2 G_f k_n): the softening branch exists.
  bool valid() const { return tensile_strength > 0 && u_failure() > u_elastic(); }
  // The tension envelope (B4).
  double envelope(double un) const {
    if (un <= u_elastic()) return kn * un;
    return std::max(0.0, tensile_strength - softening() * (un - u_elastic()));
  }
};

// The state of one vertex unit: slip and the opening where unloading last began.
struct BondVertex {
  double slip[2] = {0, 0};  // u_0 in the master face's (xi, eta)
  double u_max = 0;         // largest opening reached (<= u_E: still elastic)
};

// B4: the normal stress (tension > 0) at opening un; loading past u_max moves it.
inline double bond_normal_stress(const BondLaw& law, BondVertex& s, double un) {
  if (un <= 0) return law.kn * un;
  if (un >= s.u_max) {
    if (un > law.u_elastic()) s.u_max = std::min(un, law.u_failure());
    return law.envelope(un);
  }
  if (s.u_max <= law.u_elastic()) return law.kn * un;
  return law.envelope(s.u_max) / s.u_max * un;  // unloading towards the origin
}

// B3: the shear stress vector tau (in xi, eta) at tangential displacement ut under normal stress
// sigma (tension > 0); moves the slip when the Coulomb limit is exceeded.
inline void bond_shear_stress(const BondLaw& law, BondVertex& s, const double ut[2], double sigma, double tau[2]) {
  double d0 = ut[0] - s.slip[0], d1 = ut[1] - s.slip[1];
  const double d2 = d0 * d0 + d1 * d1;
  const double limit = std::max(0.0, law.cohesion - sigma * law.friction);
  // Far inside the limit (almost every evaluation) the square root is not needed; near it the test
  // is made as written, so the slip starts at the same bits.
  if (law.ks * law.ks * d2 < 0.99 * limit * limit) {
    tau[0] = law.ks * d0, tau[1] = law.ks * d1;
    return;
  }
  const double dn = std::sqrt(d2);
  if (law.ks * dn > limit) {
    const double ua = dn - limit / law.ks, f = ua / dn;
    s.slip[0] += f * d0, s.slip[1] += f * d1;
    d0 -= f * d0, d1 -= f * d1;
  }
  tau[0] = law.ks * d0, tau[1] = law.ks * d1;
}

// 0 while elastic, rising to 1 at failure: the share of the softening branch consumed.
inline double bond_damage(const BondLaw& law, const BondVertex& s) {
  if (s.u_max <= law.u_elastic()) return 0;
  return std::min(1.0, (s.u_max - law.u_elastic()) / (law.u_failure() - law.u_elastic()));
}

}  // namespace tessera
