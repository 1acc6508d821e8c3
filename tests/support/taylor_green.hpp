// SPDX-License-Identifier: MIT
// The Taylor-Green vortex for flow tests: single phase, periodic in x and y on (0, 2 pi)^2, one cell
// thick; u = sin x cos y, v = -cos x sin y decaying as exp(-2 nu t). Advanced with dt = 0.25 h^2 (so
// the time error falls as a second-order space error).
#pragma once
#include <cmath>
#include <memory>

#include "core/decomposition.hpp"
#include "fluid/flow_solver.hpp"

namespace tessera::test {

inline constexpr double kTaylorGreenL = 2 * M_PI;

// The solver on decomp (a box (0, L) x (0, L) x (0, L / n)), at t = 0; with energy_budget, the
// stages' energy changes measured (FlowSettings::energy_budget).
inline std::unique_ptr<FlowSolver> taylor_green(const Decomposition& decomp, int n, double nu, bool energy_budget = false) {
  FlowSettings st;
  st.cells = {n, n, 1};
  for (auto& b : st.boundaries) b = {BoundaryKind::periodic, BoundaryKind::periodic};
  st.boundaries[2] = {BoundaryKind::free_slip, BoundaryKind::free_slip};
  st.gravity = {};
  st.gas = {1.0, nu};
  st.liquid = {1.0, nu};
  st.poisson.rtol = 1e-12;
  st.energy_budget = energy_budget;
  auto s = std::make_unique<FlowSolver>(decomp, st);
  const FluidGrid& g = s->grid();
  s->initialize([&](int i, int j, int k) {
    const Vec3 x = g.centre(i, j, k);
    return FlowSolver::CellState{0.0, {std::sin(x.x) * std::cos(x.y), -std::cos(x.x) * std::sin(x.y), 0}};
  });
  return s;
}

// Advances to `end` in steps of at most 0.25 h^2.
inline void advance_taylor_green(FlowSolver& s, int n, double end) {
  const double h = kTaylorGreenL / n;
  const int steps = int(std::ceil(end / (0.25 * h * h)));
  for (int t = 0; t < steps; ++t) s.advance(end / steps);
}

}  // namespace tessera::test
