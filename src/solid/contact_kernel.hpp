// SPDX-License-Identifier: MIT
// The contact law evaluated on a block of contacts laid out in lanes (structure of arrays): the
// gather and the in-order force accumulation stay in the solver; this loop vectorises. It is
// compiled for AVX-512, AVX2 and the baseline ISA and chosen at run time (GCC target_clones).
// With -ffp-contract=off every clone performs the same IEEE operations in the same order, so the
// results are bitwise identical whatever the machine: rank-count independence holds on mixed
// clusters too.
#pragma once
#include <cstddef>

#include "solid/contact_model.hpp"

namespace tessera {

struct ContactLanes {
  static constexpr std::size_t width = 32;
  // in: centre difference a - b, radii, relative velocity v_a - v_b, R_a w_a + R_b w_b, spring xi,
  //     law coefficients; out: force on a, n x force, updated xi.
  alignas(64) double dx[width], dy[width], dz[width], ra[width], rb[width];
  alignas(64) double vx[width], vy[width], vz[width], wx[width], wy[width], wz[width];
  alignas(64) double hx[width], hy[width], hz[width];
  alignas(64) double coef[ContactCoefficients::count][width];  // walls: their sets' coefficients
  alignas(64) double meff[width];                               // pairs: m* and the material pair
  alignas(64) std::int32_t pair[width];
  alignas(64) double fx[width], fy[width], fz[width], nx[width], ny[width], nz[width];

  void set_coefficients(std::size_t lane, const ContactCoefficients& c) {
    for (int q = 0; q < ContactCoefficients::count; ++q) coef[q][lane] = c.value[q];
  }
};

// Body-body contacts: lanes hold d = x_a - x_b, R_a, R_b, m* and the material pair, an index into
// `params` (ContactModel::pair_table); the law's coefficients are made in the lanes (the same
// expression, so the same bits, as a coefficient table's).
void evaluate_contacts(LawKind law, ContactLanes& lanes, std::size_t count, double dt, const PairParams* params);
// Disc-disc contacts (plane mode, normal along axis `normal`): lanes as body-body contacts', read
// and written in the plane's components only (d, v and the spring in-plane, w about the normal; the
// force in-plane and n x F along the normal): the others are neither read nor written.
void evaluate_disc_contacts(LawKind law, int normal, ContactLanes& lanes, std::size_t count, double dt,
                            const PairParams* params);
// Body-wall contacts: lanes hold the unit normal (wall to body) in d, R in ra and the overlap in rb;
// v and w are the body's v and R w.
void evaluate_wall_contacts(LawKind law, ContactLanes& lanes, std::size_t count, double dt);

}  // namespace tessera
