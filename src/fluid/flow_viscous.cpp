// SPDX-License-Identifier: MIT
// The viscous stage (FlowSolver's members; docs/theory.md F8, F8a): the explicit variable-viscosity
// stress on the advected velocity, the wall law on no-slip walls, and the walls' share of the
// stress for the momentum budget (C8).
#include <algorithm>
#include <cmath>

#include "fluid/flow_cells.hpp"
#include "fluid/flow_solver.hpp"

namespace tessera {

using flow_cells::face_viscosity;
using flow_cells::for_box;
using flow_cells::for_wall_layers;

namespace {

// tau_qd / mu_f on the face between cells c - sd and c (F8): the derivative normal to the face
// compact (doubled when q = d), the transposed one the mean of the two cells' central differences
// (cross = 1 / (4 h_q); 0 when q = d).
inline double face_strain(const double* uq, const double* ud, std::size_t c, std::ptrdiff_t sd, std::ptrdiff_t sq,
                          double inv_h, double cross, bool normal) {
  const double grad = (uq[c] - uq[c - sd]) * inv_h;
  if (normal) return 2 * grad;
  return grad + ((ud[c + sq] - ud[c - sq]) + (ud[c - sd + sq] - ud[c - sd - sq])) * cross;
}

}  // namespace

void FlowSolver::viscous(double dt) {
  const FluidGrid& g = *grid_;
  const double h[3] = {g.h(0), g.h(1), g.h(2)};
  const int i0 = g.begin(0), i1 = g.end(0);
  // Face viscosities once per step (low face of each owned cell and the last high face); the flux
  // buffers of the advection are free now.
  auto& mu_face = flux_q_;
  for (int d = 0; d < 3; ++d) {
    const std::ptrdiff_t sd = g.stride(d);
    std::array<int, 3> hi{g.end(0), g.end(1), g.end(2)};
    hi[d] += 1;
    for (int k = g.begin(2); k < hi[2]; ++k)
      for (int j = g.begin(1); j < hi[1]; ++j) {
        const std::size_t row = g.at(0, j, k);
        const double* mu = mu_.data();
        double* mf = mu_face[d].data();
        for (int i = i0; i < hi[0]; ++i) mf[row + i] = face_viscosity(mu[row + i], mu[row + i - sd]);
      }
  }
  // div(tau)_q = sum_d (tau_qd(high) - tau_qd(low)) / h_d, tau_qd = mu_f (du_q/dx_d + du_d/dx_q):
  // the normal derivative compact, the transposed one from the two cells' central differences.
  for (int q = 0; q < 3; ++q) {
    double* acc = work_[q].data();
    for (int k = g.begin(2); k < g.end(2); ++k)
      for (int j = g.begin(1); j < g.end(1); ++j) {
        const std::size_t row = g.at(0, j, k);
        for (int i = i0; i < i1; ++i) acc[row + i] = 0;
      }
    for (int d = 0; d < 3; ++d) {
      const std::ptrdiff_t sd = g.stride(d), sq = g.stride(q);
      const double inv_h = 1 / h[d], cross = q == d ? 0.0 : 1 / (4 * h[q]);
      const double* uq = u_[q].data();
      const double* ud = u_[d].data();
      const double* mf = mu_face[d].data();
      for (int k = g.begin(2); k < g.end(2); ++k)
        for (int j = g.begin(1); j < g.end(1); ++j) {
          const std::size_t row = g.at(0, j, k);
          for (int i = i0; i < i1; ++i) {
            const std::size_t c = row + i;
            const double t_lo = face_strain(uq, ud, c, sd, sq, inv_h, cross, q == d);
            const double t_hi = face_strain(uq, ud, c + sd, sd, sq, inv_h, cross, q == d);
            acc[c] += (mf[c + sd] * t_hi - mf[c] * t_lo) * inv_h;
          }
        }
    }
    // The walls' share: the stress on the wall faces, times their area and dt (the momentum budget).
    for_wall_layers(g, [&](int d, int side, const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
      const std::ptrdiff_t sd = g.stride(d), sq = g.stride(q);
      const double inv_h = 1 / h[d], cross = q == d ? 0.0 : 1 / (4 * h[q]), area = h[0] * h[1] * h[2] * inv_h;
      const double* uq = u_[q].data();
      const double* ud = u_[d].data();
      const double* mf = mu_face[d].data();
      for_box(lo, hi, [&](int i, int j, int k) {
        const std::size_t c = g.at(i, j, k), face = side == 0 ? c : c + sd;
        const double stress = mf[face] * face_strain(uq, ud, face, sd, sq, inv_h, cross, q == d);
        wall_impulse_[q] += (side == 0 ? -stress : stress) * area * dt;
      });
    });
    if (!stress_div_[q].empty()) std::copy(work_[q].begin(), work_[q].end(), stress_div_[q].begin());
    const double* uq = u_[q].data();
    const double* rho = rho_.data();
    for (int k = g.begin(2); k < g.end(2); ++k)
      for (int j = g.begin(1); j < g.end(1); ++j) {
        const std::size_t row = g.at(0, j, k);
        for (int i = i0; i < i1; ++i) acc[row + i] = uq[row + i] + dt * acc[row + i] / rho[row + i];
      }
  }
  if (settings_.wall_model == FlowSettings::WallModel::spalding) wall_model_stress(dt);
  for (int q = 0; q < 3; ++q) std::swap(u_[q], work_[q]);
  g.exchange({&u_[0], &u_[1], &u_[2]});
  fill_velocity_ghosts(u_);
}

double spalding_stress_factor(double speed, double y, double nu) {
  constexpr double kappa = 0.41, b = 5.2;
  const double reynolds = speed * y / nu;  // = u+ y+
  if (!(reynolds > 1e-12)) return 1;
  const double e = std::exp(-kappa * b), log_re = std::log(reynolds);
  // G(u+) = ln(u+ y+(u+)) - ln(reynolds), y+(u+) by Spalding, rises with u+; its root is unique and
  // lies in (0, sqrt(reynolds)] because y+ >= u+. Newton on the logarithm (y+ grows like
  // exp(kappa u+)), kept inside the bracket by bisection.
  auto residual = [&](double up, double& slope) {
    const double k = kappa * up, ek = std::exp(k);
    const double yplus = up + e * (ek - 1 - k - k * k / 2 - k * k * k / 6);
    const double dyplus = 1 + e * kappa * (ek - 1 - k - k * k / 2);
    slope = dyplus / yplus + 1 / up;
    return std::log(up * yplus) - log_re;
  };
  double lo = 0, hi = std::sqrt(reynolds), up = hi;
  for (int it = 0; it < 200; ++it) {
    double slope;
    const double r = residual(up, slope);
    if (r < 0) {
      lo = up;
    } else {
      hi = up;
    }
    double next = up - r / slope;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - up) <= 1e-14 * up;
    up = next;
    if (done) break;
  }
  return std::max(1.0, reynolds / (up * up));
}

// The viscous step put mu_w 2 u_t / h^2 (mu_w: the wall face's viscosity, the cell's own) into the
// wall cells' explicit stress. Take it out and put in the wall law's stress, implicit in u_t:
//   u_t <- (u_t* + dt mu_w 2 u_t / (rho h^2)) / (1 + dt mu_w F 2 / (rho h^2)),
// F = spalding_stress_factor(|u_t|, h/2, mu/rho) from the velocity before the step.
void FlowSolver::wall_model_stress(double dt) {
  const FluidGrid& g = *grid_;
  for_wall_layers(g, [&](int d, int side, const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    if (g.boundary(d, side) != BoundaryKind::no_slip) return;
    const double h = g.h(d), y = h / 2;
    for_box(lo, hi, [&](int i, int j, int k) {
      const std::size_t c = g.at(i, j, k);
      double speed2 = 0;
      for (int q = 0; q < 3; ++q)
        if (q != d) speed2 += u_[q][c] * u_[q][c];
      const double mu = mu_[c], rho = rho_[c];
      const double factor = spalding_stress_factor(std::sqrt(speed2), y, mu / rho);
      const double laminar = dt * 2 * mu / (rho * h * h);
      const double mass = rho * g.h(0) * g.h(1) * g.h(2);
      for (int q = 0; q < 3; ++q)
        if (q != d) {
          const double before = work_[q][c];
          work_[q][c] = (work_[q][c] + laminar * u_[q][c]) / (1 + laminar * factor);
          wall_impulse_[q] += mass * (work_[q][c] - before);  // the law's stress in place of F8's
        }
    });
  });
}

}  // namespace tessera
