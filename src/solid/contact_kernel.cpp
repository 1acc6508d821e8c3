// SPDX-License-Identifier: MIT
#include "solid/contact_kernel.hpp"

#include "solid/kernel_mirrors.hpp"

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

// Discs with the plane's normal along axis N (plane mode, T15): the lanes' in-plane components
// (u, v: kernel_mirrors.hpp) and the spin about the normal; the force's in-plane components and the
// normal component of n x F out. The 3D loop's steps without its zero terms (W e_N x n in the plane:
// (W n_v, 0 - W n_u) for N = y, (0 - W n_v, W n_u) otherwise, as the 3D cross product's terms fall).
template <class Law, int N, class Coefficients>
inline void evaluate_disc(ContactLanes& L, std::size_t count, double dt, Coefficients&& coefficients) {
  constexpr int U = plane_u(N), V = plane_v(N);
  double* const d[3] = {L.dx, L.dy, L.dz};
  double* const vel[3] = {L.vx, L.vy, L.vz};
  double* const spin[3] = {L.wx, L.wy, L.wz};
  double* const h[3] = {L.hx, L.hy, L.hz};
  double* const f[3] = {L.fx, L.fy, L.fz};
  double* const nf[3] = {L.nx, L.ny, L.nz};
  double *const du = d[U], *const dv = d[V], *const vu = vel[U], *const vv = vel[V], *const wn = spin[N];
  double *const hu = h[U], *const hv = h[V], *const fu = f[U], *const fv = f[V], *const tn = nf[N];
  for (std::size_t j = 0; j < count; ++j) {
    const PlaneVector dd{du[j], dv[j]};
    const double r = std::sqrt(norm2(dd));
    const PlaneVector nrm = dd * (1.0 / r);
    const double delta = L.ra[j] + L.rb[j] - r;
    const double w = wn[j];
    const PlaneVector turn = N == 1 ? PlaneVector{w * nrm.v, 0.0 - w * nrm.u} : PlaneVector{0.0 - w * nrm.v, w * nrm.u};
    const PlaneVector v_rel = PlaneVector{vu[j], vv[j]} - turn;
    const typename Law::Coefficients c = coefficients(j);
    PlaneVector xi{hu[j], hv[j]};
    const PlaneVector force = contact_force<Law>(c, delta, nrm, v_rel, dt, xi);
    hu[j] = xi.u, hv[j] = xi.v;
    fu[j] = force.u, fv[j] = force.v;
    tn[j] = N == 1 ? nrm.v * force.u - nrm.u * force.v : nrm.u * force.v - nrm.v * force.u;
  }
}

template <class Law>
typename Law::Coefficients from_lanes(const ContactLanes& L, std::size_t j) {
  return {L.coef[0][j], L.coef[1][j], L.coef[2][j], L.coef[3][j], L.coef[4][j]};
}

// Pairs: the coefficients from the material pair, m* and R* = R_a R_b / (R_a + R_b) (the same
// expression as a coefficient table's, so the same bits). A block of one material pair (the usual
// case) makes them in the vectorised loop; a mixed block first fills the coefficient lanes.
template <class Law, class Block>
inline void evaluate_pairs(ContactLanes& L, std::size_t count, const PairParams* params, Block&& block) {
  bool uniform = true;
  for (std::size_t j = 1; j < count; ++j) uniform = uniform && L.pair[j] == L.pair[0];
  if (uniform && count > 0) {
    const PairParams p = params[L.pair[0]];
    block([&](std::size_t j) { return Law::coefficients(p, L.meff[j], L.ra[j] * L.rb[j] / (L.ra[j] + L.rb[j])); });
    return;
  }
  for (std::size_t j = 0; j < count; ++j) {
    const auto c = ContactCoefficients::of<Law>(
        Law::coefficients(params[L.pair[j]], L.meff[j], L.ra[j] * L.rb[j] / (L.ra[j] + L.rb[j])));
    L.set_coefficients(j, c);
  }
  block([&](std::size_t j) { return from_lanes<Law>(L, j); });
}

template <class Law>
inline void evaluate_pairs(ContactLanes& L, std::size_t count, double dt, const PairParams* params) {
  evaluate_pairs<Law>(L, count, params, [&](auto&& c) { evaluate<Law, false>(L, count, dt, c); });
}

template <class Law, int N>
inline void evaluate_discs(ContactLanes& L, std::size_t count, double dt, const PairParams* params) {
  evaluate_pairs<Law>(L, count, params, [&](auto&& c) { evaluate_disc<Law, N>(L, count, dt, c); });
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

#define TESSERA_DISC_KERNELS(name, Law)                                                                  \
  TESSERA_CLONES void name##_0(ContactLanes& l, std::size_t n, double dt, const PairParams* p) {         \
    evaluate_discs<Law, 0>(l, n, dt, p);                                                               \
  }                                                                                                    \
  TESSERA_CLONES void name##_1(ContactLanes& l, std::size_t n, double dt, const PairParams* p) {         \
    evaluate_discs<Law, 1>(l, n, dt, p);                                                               \
  }                                                                                                    \
  TESSERA_CLONES void name##_2(ContactLanes& l, std::size_t n, double dt, const PairParams* p) {         \
    evaluate_discs<Law, 2>(l, n, dt, p);                                                               \
  }
TESSERA_DISC_KERNELS(evaluate_linear_discs, LinearSpringDashpot)
TESSERA_DISC_KERNELS(evaluate_hertz_discs, HertzMindlin)
#undef TESSERA_DISC_KERNELS

// Each law's clones, by overload (the registry, with_law, picks the law).
using Kernel = void (*)(ContactLanes&, std::size_t, double, const PairParams*);
Kernel kernel(LinearSpringDashpot, bool wall) { return wall ? evaluate_linear_wall : evaluate_linear; }
Kernel kernel(HertzMindlin, bool wall) { return wall ? evaluate_hertz_wall : evaluate_hertz; }
Kernel disc_kernel(LinearSpringDashpot, int normal) {
  return normal == 0 ? evaluate_linear_discs_0 : normal == 1 ? evaluate_linear_discs_1 : evaluate_linear_discs_2;
}
Kernel disc_kernel(HertzMindlin, int normal) {
  return normal == 0 ? evaluate_hertz_discs_0 : normal == 1 ? evaluate_hertz_discs_1 : evaluate_hertz_discs_2;
}

}  // namespace

void evaluate_contacts(LawKind law, ContactLanes& lanes, std::size_t count, double dt, const PairParams* params) {
  with_law(law, [&](auto l) { kernel(l, false)(lanes, count, dt, params); });
}

void evaluate_disc_contacts(LawKind law, int normal, ContactLanes& lanes, std::size_t count, double dt,
                            const PairParams* params) {
  with_law(law, [&](auto l) { disc_kernel(l, normal)(lanes, count, dt, params); });
}

void evaluate_wall_contacts(LawKind law, ContactLanes& lanes, std::size_t count, double dt) {
  with_law(law, [&](auto l) { kernel(l, true)(lanes, count, dt, nullptr); });
}

}  // namespace tessera
