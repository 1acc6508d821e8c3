// SPDX-License-Identifier: MIT
#include "solid/contact_kernel.hpp"

namespace tessera {

namespace {

// One block of contacts; coefficients(j) gives lane j's law coefficients.
template <class Law, bool wall, class Coefficients>
inline void evaluate(ContactLanes& L, std::size_t count, double dt, Coefficients&& coefficients) {
  for (std::size_t j = 0; j < count; ++j) {
    const Vec3 d{L.dx[j], L.dy[j], L.dz[j]};
    double delta = L.rb[j];
    Vec3 nrm = d;
    if constexpr (!wall) {
      const double r = std::sqrt(norm2(d));
      nrm = d * (1.0 / r);
      delta = L.ra[j] + L.rb[j] - r;
    }
    const Vec3 v_rel = Vec3{L.vx[j], L.vy[j], L.vz[j]} - cross(Vec3{L.wx[j], L.wy[j], L.wz[j]}, nrm);
    const typename Law::Coefficients c = coefficients(j);
    Vec3 xi{L.hx[j], L.hy[j], L.hz[j]};
    const Vec3 force = contact_force<Law>(c, delta, nrm, v_rel, dt, xi);
    const Vec3 nf = cross(nrm, force);
    L.hx[j] = xi.x, L.hy[j] = xi.y, L.hz[j] = xi.z;
    L.fx[j] = force.x, L.fy[j] = force.y, L.fz[j] = force.z;
    L.nx[j] = nf.x, L.ny[j] = nf.y, L.nz[j] = nf.z;
  }
}

template <class Law>
typename Law::Coefficients from_lanes(const ContactLanes& L, std::size_t j) {
  return {L.coef[0][j], L.coef[1][j], L.coef[2][j], L.coef[3][j], L.coef[4][j]};
}

// Pairs: the coefficients from the material pair, m* and R* = R_a R_b / (R_a + R_b) (the same
// expression as a coefficient table's, so the same bits). A block of one material pair (the usual
// case) makes them in the vectorised loop; a mixed block first fills the coefficient lanes.
template <class Law>
inline void evaluate_pairs(ContactLanes& L, std::size_t count, double dt, const PairParams* params) {
  bool uniform = true;
  for (std::size_t j = 1; j < count; ++j) uniform = uniform && L.pair[j] == L.pair[0];
  if (uniform && count > 0) {
    const PairParams p = params[L.pair[0]];
    evaluate<Law, false>(L, count, dt, [&](std::size_t j) {
      return Law::coefficients(p, L.meff[j], L.ra[j] * L.rb[j] / (L.ra[j] + L.rb[j]));
    });
    return;
  }
  for (std::size_t j = 0; j < count; ++j) {
    const auto c = ContactCoefficients::of<Law>(
        Law::coefficients(params[L.pair[j]], L.meff[j], L.ra[j] * L.rb[j] / (L.ra[j] + L.rb[j])));
    L.set_coefficients(j, c);
  }
  evaluate<Law, false>(L, count, dt, [&](std::size_t j) { return from_lanes<Law>(L, j); });
}

template <class Law>
inline void evaluate_walls(ContactLanes& L, std::size_t count, double dt) {
  evaluate<Law, true>(L, count, dt, [&](std::size_t j) { return from_lanes<Law>(L, j); });
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
// flatten: the law and vector helpers must be compiled inside each clone, for its ISA.
#define TESSERA_CLONES __attribute__((target_clones("avx512f", "avx2", "default"), flatten))
#else
#define TESSERA_CLONES
#endif

TESSERA_CLONES void evaluate_linear(ContactLanes& lanes, std::size_t count, double dt, const PairParams* params) {
  evaluate_pairs<LinearSpringDashpot>(lanes, count, dt, params);
}

TESSERA_CLONES void evaluate_hertz(ContactLanes& lanes, std::size_t count, double dt, const PairParams* params) {
  evaluate_pairs<HertzMindlin>(lanes, count, dt, params);
}

TESSERA_CLONES void evaluate_linear_wall(ContactLanes& lanes, std::size_t count, double dt, const PairParams*) {
  evaluate_walls<LinearSpringDashpot>(lanes, count, dt);
}

TESSERA_CLONES void evaluate_hertz_wall(ContactLanes& lanes, std::size_t count, double dt, const PairParams*) {
  evaluate_walls<HertzMindlin>(lanes, count, dt);
}

// Each law's clones, by overload (the registry, with_law, picks the law).
using Kernel = void (*)(ContactLanes&, std::size_t, double, const PairParams*);
Kernel kernel(LinearSpringDashpot, bool wall) { return wall ? evaluate_linear_wall : evaluate_linear; }
Kernel kernel(HertzMindlin, bool wall) { return wall ? evaluate_hertz_wall : evaluate_hertz; }

}  // namespace

void evaluate_contacts(LawKind law, ContactLanes& lanes, std::size_t count, double dt, const PairParams* params) {
  with_law(law, [&](auto l) { kernel(l, false)(lanes, count, dt, params); });
}

void evaluate_wall_contacts(LawKind law, ContactLanes& lanes, std::size_t count, double dt) {
  with_law(law, [&](auto l) { kernel(l, true)(lanes, count, dt, nullptr); });
}

}  // namespace tessera
