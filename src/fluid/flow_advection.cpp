// SPDX-License-Identifier: MIT
// The advection stage (FlowSolver's members; docs/theory.md F4-F7): split sweeps that move the
// liquid fraction through PLIC slabs and the momentum with the same mass fluxes, the van Leer
// limited face velocity, and F7's a-posteriori bound on each cell's new velocity.
#include <algorithm>
#include <cmath>

#include "fluid/flow_cells.hpp"
#include "fluid/flow_solver.hpp"
#include "fluid/plic.hpp"

namespace tessera {

using flow_cells::for_box;
using flow_cells::kEmpty;
using flow_cells::kFull;

namespace {

// F7's bound on a cell's new velocity: the range of the old ones widened by this share of their
// magnitudes (the dilatation term moves an upwind update off the range by the Poisson tolerance).
constexpr double kMomentumBoundSlack = 1e-12;

// van Leer limited slope from the two one-sided differences.
inline double van_leer(double a, double b) { return a * b > 0 ? 2 * a * b / (a + b) : 0.0; }

}  // namespace

void FlowSolver::advect(double dt) {
  const FluidGrid& g = *grid_;
  auto t = timers_.scope("advection");
  // Weymouth & Yue's cell-centred indicator, from the start of the step (F4).
  for (std::size_t c = 0; c < f_.size(); ++c) indicator_[c] = f_[c] > 0.5 ? 1.0 : 0.0;
  // The sweep order alternates from step to step (x y z, then z y x).
  const int order[2][3] = {{0, 1, 2}, {2, 1, 0}};
  std::vector<int> active;
  for (int d : order[parity_++ % 2])
    if (g.cells()[d] > 1 || g.periodic(d)) active.push_back(d);  // a one-cell slab between walls: no flow
  std::fill(dilatation_.begin(), dilatation_.end(), 0.0);
  for (int q = 0; q < 3; ++q) std::copy(u_[q].begin(), u_[q].end(), work_[q].begin());  // F7's u at the step's start
  for (std::size_t n = 0; n < active.size(); ++n) sweep(active[n], dt, n + 1 == active.size());
  update_properties();
}

void FlowSolver::sweep(int d, double dt, bool last) {
  const FluidGrid& g = *grid_;
  reconstruct(d);
  const double h = g.h(d);
  const std::ptrdiff_t st = g.stride(d);
  const double rg = settings_.gas.density, dr = settings_.liquid.density - rg;
  const auto& uf = uf_[d];
  // Face fluxes on the faces of owned cells along d: low faces and the last high face.
  std::array<int, 3> lo{g.begin(0), g.begin(1), g.begin(2)}, hi{g.end(0), g.end(1), g.end(2)};
  hi[d] += 1;
  for_box(lo, hi, [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    const double v = uf[c];
    const double s = std::abs(v) * dt / h;  // slab thickness in cell widths
    const bool forward = v > 0;
    const std::size_t up = forward ? c - st : c;
    const double fu = f_[up];
    double vol = 0;
    if (s > 0) {
      if (fu >= 1 - kFull)
        vol = s;
      else if (fu > kEmpty) {
        const double n[3] = {plic_[0][up], plic_[1][up], plic_[2][up]};
        vol = plic::slab_volume(n, plic_[3][up], d, s, forward);
      }
    }
    const double flux_f = forward ? vol : -vol;           // liquid, per cell volume, towards +d
    const double flux_m = rg * v * dt / h + dr * flux_f;  // mass, per cell volume (F6)
    flux_f_[c] = flux_f;
    flux_m_[c] = flux_m;
    // The advected velocity: the upwind value plus half its van Leer limited slope times (1 - s);
    // bound_momentum_fluxes() takes the plain upwind value where that would overshoot (F7).
    for (int q = 0; q < 3; ++q) {
      const auto& u = u_[q];
      const double face = forward ? u[c - st] + 0.5 * (1 - s) * van_leer(u[c - st] - u[c - 2 * st], u[c] - u[c - st])
                                  : u[c] - 0.5 * (1 - s) * van_leer(u[c] - u[c - st], u[c + st] - u[c]);
      flux_q_[q][c] = flux_m * face;
    }
  });
  // Every cell's new state from these fluxes, into sweep_u_ and sweep_f_ (the old ones stay for the
  // bound's ranges and upwind values), and F7's first round: the cells that would overshoot.
  auto& marked = bound_marked_;
  marked.clear();
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)}, [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    const double div = sweep_dilatation(c, d, dt, last);
    if (!last) dilatation_[c] += div;
    const SweepUpdate up = sweep_update(c, st, div);
    store_update(c, up);
    if (overshoots(c, st, up)) marked.push_back({i, j, k});
  });
  // The later rounds; the cells next to a face that took the upwind value are updated again.
  bound_momentum_fluxes(d, dt, last);
  for (const auto& n : bound_redo_) {
    const std::size_t c = g.at(n[0], n[1], n[2]);
    store_update(c, sweep_update(c, st, sweep_dilatation(c, d, dt, last)));
  }
  if (!advection_source_.empty()) add_advection_source(d);
  for (int q = 0; q < 3; ++q) std::swap(u_[q], sweep_u_[q]);
  std::swap(f_, sweep_f_);
  g.exchange({&f_, &u_[0], &u_[1], &u_[2]});
  fill_fraction_ghosts(f_);
  fill_velocity_ghosts(u_);
}

void FlowSolver::add_advection_source(int d) {
  // F12a: a face with mass flux M carrying q between cells a (low) and b (high) makes the kinetic
  // energy M (u_b - u_a) (q - (u_a + u_b) / 2) per cell volume: 0 for the mean, -M (u_b - u_a)^2 / 2
  // for the upwind value. Half to each of its owned cells (a face on a cut is computed by both
  // ranks, each keeping its own cell's half).
  const FluidGrid& g = *grid_;
  const std::ptrdiff_t st = g.stride(d);
  std::array<int, 3> lo{g.begin(0), g.begin(1), g.begin(2)}, hi{g.end(0), g.end(1), g.end(2)};
  hi[d] += 1;
  for_box(lo, hi, [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    const double m = flux_m_[c];
    if (m == 0) return;
    double s = 0;
    for (int q = 0; q < 3; ++q) {
      const double a = u_[q][c - st], b = u_[q][c];
      s += (b - a) * (flux_q_[q][c] - 0.5 * m * (a + b));
    }
    const int idx = d == 0 ? i : (d == 1 ? j : k);
    if (idx < g.end(d)) advection_source_[c] += 0.5 * s;
    if (idx > g.begin(d)) advection_source_[c - st] += 0.5 * s;
  });
}

double FlowSolver::sweep_dilatation(std::size_t c, int d, double dt, bool last) const {
  // The sweeps' dilatation terms add up to dt div(u_f), zero up to the Poisson tolerance. The last
  // sweep takes minus the sum of the others, so that they cancel exactly and the liquid volume is
  // conserved to round-off whatever the tolerance (the cell's own divergence is that small).
  if (last) return -dilatation_[c];
  const std::ptrdiff_t st = grid_->stride(d);
  return (uf_[d][c + st] - uf_[d][c]) * dt / grid_->h(d);
}

FlowSolver::SweepUpdate FlowSolver::sweep_update(std::size_t c, std::ptrdiff_t st, double div) const {
  const double rg = settings_.gas.density, dr = settings_.liquid.density - rg;
  const double cc = indicator_[c];
  const double f_old = f_[c];
  SweepUpdate up;
  up.fraction = f_old - (flux_f_[c + st] - flux_f_[c]) + cc * div;  // (F4)
  up.density = rg + dr * up.fraction;
  const double rho_old = rg + dr * f_old, rho_cc = rg + dr * cc;
  for (int q = 0; q < 3; ++q)
    // The dilatation term with the velocity at the step's start (work_): the sweeps' terms then
    // cancel as their div's do, and the advection moves momentum without making any (F7).
    up.momentum[q] = rho_old * u_[q][c] - (flux_q_[q][c + st] - flux_q_[q][c]) + rho_cc * work_[q][c] * div;
  return up;
}

void FlowSolver::store_update(std::size_t c, const SweepUpdate& up) {
  for (int q = 0; q < 3; ++q) sweep_u_[q][c] = up.momentum[q] / up.density;  // (F7)
  sweep_f_[c] = up.fraction;
}

bool FlowSolver::overshoots(std::size_t c, std::ptrdiff_t st, const SweepUpdate& up) const {
  // F7's bound: the new velocity (any component) outside the range of the cell's own and its two
  // neighbours' along the sweep, widened by the slack.
  for (int q = 0; q < 3; ++q) {
    const auto& u = u_[q];
    const double lo = std::min({u[c - st], u[c], u[c + st]}), hi = std::max({u[c - st], u[c], u[c + st]});
    const double slack = kMomentumBoundSlack * (std::abs(lo) + std::abs(hi)) + 1e-14;
    if (up.momentum[q] < (lo - slack) * up.density || up.momentum[q] > (hi + slack) * up.density) return true;
  }
  return false;
}

void FlowSolver::bound_momentum_fluxes(int d, double dt, bool last) {
  // F7's bound: a cell whose new velocity would overshoot (bound_marked_ holds the first round's,
  // from sweep()) takes the plain upwind value on both its faces, which makes its update a convex
  // combination of those velocities. Marks only grow, so the rounds end (at worst with every face
  // upwind); the marks are exchanged so that both ranks of a face choose alike. A round checks only
  // the cells next to the ones just marked (the rest of the fluxes did not change). bound_redo_
  // gets every owned cell next to a face that changed, whose update sweep() makes again.
  const FluidGrid& g = *grid_;
  const std::ptrdiff_t st = g.stride(d);
  const auto& uf = uf_[d];
  auto upwind_face = [&](std::size_t face) {
    const std::size_t up = uf[face] > 0 ? face - st : face;
    for (int q = 0; q < 3; ++q) flux_q_[q][face] = flux_m_[face] * u_[q][up];
  };
  std::fill(upwind_cell_.begin(), upwind_cell_.end(), 0.0);
  auto& marked = bound_marked_;
  auto& check = bound_check_;
  auto& redo = bound_redo_;
  redo.clear();
  auto owned = [&](const std::array<int, 3>& n) { return n[d] >= g.begin(d) && n[d] < g.end(d); };
  for (double round = 1;; ++round) {
    for (const auto& m : marked) upwind_cell_[g.at(m[0], m[1], m[2])] = round;
    if (g.reduce_sum(static_cast<double>(marked.size())) == 0) return;
    g.exchange(upwind_cell_);
    // The faces of the cells just marked take the upwind value, and their unmarked owned
    // neighbours along d are checked again; a cell just marked on the next rank (a ghost) does the
    // same to the face it shares with this rank's cell.
    check.clear();
    auto neighbour = [&](std::array<int, 3> n) {
      if (!owned(n)) return;
      redo.push_back(n);
      if (upwind_cell_[g.at(n[0], n[1], n[2])] == 0) check.push_back(n);
    };
    for (const auto& m : marked) {
      const std::size_t c = g.at(m[0], m[1], m[2]);
      upwind_face(c);
      upwind_face(c + st);
      redo.push_back(m);
      std::array<int, 3> n = m;
      n[d] = m[d] - 1, neighbour(n);
      n[d] = m[d] + 1, neighbour(n);
    }
    std::array<int, 3> lo{g.begin(0), g.begin(1), g.begin(2)}, hi{g.end(0), g.end(1), g.end(2)};
    for (const int ghost : {g.begin(d) - 1, g.end(d)}) {
      lo[d] = ghost, hi[d] = ghost + 1;
      for_box(lo, hi, [&](int i, int j, int k) {
        const std::size_t c = g.at(i, j, k);
        if (upwind_cell_[c] != round) return;
        upwind_face(ghost < g.begin(d) ? c + st : c);
        std::array<int, 3> n{i, j, k};
        n[d] = ghost < g.begin(d) ? ghost + 1 : ghost - 1;
        neighbour(n);
      });
    }
    marked.clear();
    for (const auto& n : check) {
      const std::size_t c = g.at(n[0], n[1], n[2]);
      if (upwind_cell_[c] != 0) continue;  // not checked twice if listed twice
      if (overshoots(c, st, sweep_update(c, st, sweep_dilatation(c, d, dt, last)))) {
        upwind_cell_[c] = round + 1;
        marked.push_back(n);
      }
    }
  }
}

}  // namespace tessera
