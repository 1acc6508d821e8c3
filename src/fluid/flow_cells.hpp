// SPDX-License-Identifier: MIT
// What the flow solver's source files share about cells (not part of its interface).
#pragma once
#include <array>

#include "fluid/fluid_grid.hpp"

namespace tessera::flow_cells {

// Cells with f below kEmpty or above 1 - kEmpty carry no interface (round-off residue of the
// split advection; their volume stays counted, none is clipped).
constexpr double kEmpty = 1e-12;

// A cell the liquid fills keeps f = 1 only to the Poisson tolerance: the last sweep's dilatation
// (F4) leaves dt div(u_f) in it, so a bulk cell passes 1 - kEmpty within some hundred steps
// (measured: 1 - 3.1e-12 after 240 steps in the packed bed of docs/validation.md, 1 + 6.8e-10 after
// 150 in the pool drop). Within kFull of 1 a cell is liquid throughout for the momentum advection's
// limiter, so that this residue does not switch a bulk cell's scheme (the switch moved the packed
// bed's flow by 4e-4 of its speed in a few cells, differently on 1 and 2 ranks). Its gas is at most
// kFull rho_g / rho_l (1e-9 for air and water) of its mass. Empty cells do not drift (no flux).
constexpr double kFull = 1e-6;

// A cell holds an interface (a PLIC plane, a Youngs normal, an interface potential) when f lies
// between kEmpty and 1 - kFull. A bulk liquid cell's residue of 1e-12 to 1e-9 (above) is not an
// interface: its Youngs normal is the gradient of that residue, noise, and treating it as one made
// every cell of a pool an interface cell (the pool drop's lower rank took 1.9 times the upper's
// interface work; docs/performance.md, 2026-12-03). It fluxes as a full cell, the whole slab: the
// flux is the same number leaving one cell and entering the next, so the volume stays exact.
inline bool holds_interface(double f) { return f > kEmpty && f < 1 - kFull; }

// Face viscosity: the harmonic mean of the two cells'. Exact for shear along a layered interface
// (stresses in series) and bounded by twice the smaller viscosity, so that a gas cell beside the
// interface keeps close to the gas's explicit viscous limit; the arithmetic mean would give it
// half the liquid's viscosity over the gas's density (30 times the gas's nu for air and water).
inline double face_viscosity(double a, double b) { return a + b > 0 ? 2 * a * b / (a + b) : 0.0; }

// Loops over a box of global indices [lo, hi) in k, j, i order.
template <class F>
void for_box(const std::array<int, 3>& lo, const std::array<int, 3>& hi, F&& fn) {
  for (int k = lo[2]; k < hi[2]; ++k)
    for (int j = lo[1]; j < hi[1]; ++j)
      for (int i = lo[0]; i < hi[0]; ++i) fn(i, j, k);
}

// fn(d, side, lo, hi) for each side of the domain that this rank's cells touch and that is closed
// (neither periodic nor outflow): [lo, hi) is the layer of owned cells along it.
template <class F>
void for_wall_layers(const FluidGrid& g, F&& fn) {
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      if (!g.at_domain_edge(d, side) || g.boundary(d, side) == BoundaryKind::outflow) continue;
      std::array<int, 3> lo{g.begin(0), g.begin(1), g.begin(2)}, hi{g.end(0), g.end(1), g.end(2)};
      lo[d] = side == 0 ? 0 : g.cells()[d] - 1;
      hi[d] = lo[d] + 1;
      fn(d, side, lo, hi);
    }
}

}  // namespace tessera::flow_cells
