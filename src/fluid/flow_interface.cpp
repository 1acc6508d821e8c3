// SPDX-License-Identifier: MIT
// The interface in the cells (FlowSolver's members; docs/theory.md F5, F10b): Youngs' normals, the
// PLIC planes the advection sweeps use, and the gravity potential of the interface that balances
// gravity across a density jump in the projection.
#include <algorithm>
#include <cmath>
#include <limits>

#include "fluid/flow_cells.hpp"
#include "fluid/flow_solver.hpp"
#include "fluid/plic.hpp"

namespace tessera {

using flow_cells::for_box;
using flow_cells::kEmpty;

// Youngs' normal: minus the gradient of f averaged over the cell's eight corners, in index space
// (the unit-cube map of the cell), weights 1-2-1 across (F5).
void FlowSolver::youngs_normal(std::size_t c, double n[3]) const {
  const FluidGrid& g = *grid_;
  const std::ptrdiff_t sx = g.stride(0), sy = g.stride(1), sz = g.stride(2);
  n[0] = n[1] = n[2] = 0;
  for (int b = -1; b <= 1; ++b)
    for (int a = -1; a <= 1; ++a) {
      const double w = (a == 0 ? 2.0 : 1.0) * (b == 0 ? 2.0 : 1.0);
      n[0] += w * (f_[c - sx + a * sy + b * sz] - f_[c + sx + a * sy + b * sz]);
      n[1] += w * (f_[c - sy + a * sx + b * sz] - f_[c + sy + a * sx + b * sz]);
      n[2] += w * (f_[c - sz + a * sx + b * sy] - f_[c + sz + a * sx + b * sy]);
    }
}

// phi = g . (x - lo) at the point (a, b, c) in cell widths from lo (cell (i, j, k)'s centre is
// (i + 1/2, j + 1/2, k + 1/2)).
double FlowSolver::potential(double a, double b, double c) const {
  const FluidGrid& g = *grid_;
  const Vec3& gv = settings_.gravity;
  return gv.x * a * g.h(0) + gv.y * b * g.h(1) + gv.z * c * g.h(2);
}

// The gravity potential phi = g . (x - lo) at a point of each interface cell's interface (F10b), in
// the owned cells and, exchanged, the ghosts; NaN where the cell holds no interface.
void FlowSolver::interface_potential() {
  const FluidGrid& g = *grid_;
  const Vec3 gv = settings_.gravity;
  if (interface_phi_.size() != f_.size()) interface_phi_.assign(f_.size(), 0.0);
  g2_ = dot(gv, gv);
  h_max_ = std::max({g.h(0), g.h(1), g.h(2)});
  down_axis_ = 0;
  for (int q = 1; q < 3; ++q)
    if (std::abs(gv[q]) > std::abs(gv[down_axis_])) down_axis_ = q;
  constexpr double kColumnEnd = 0.01;  // a column's end cell counts as full or empty within this
  std::fill(interface_phi_.begin(), interface_phi_.end(), std::numeric_limits<double>::quiet_NaN());
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)},
          [&](int i, int j, int k) {
            const std::size_t c = g.at(i, j, k);
            const double fc = f_[c];
            if (!flow_cells::holds_interface(fc)) return;
            double phi = potential(i + 0.5, j + 0.5, k + 0.5);
            // The height function along gravity's main direction: where the column through the cell
            // reaches a full cell below and an empty one above within two cells each way (or the
            // reverse: liquid above gas), the interface lies at the height their fractions add up
            // to, at the cell's centre across: exact for a plane of slope up to 1 against the axis.
            {
              const std::ptrdiff_t st = g.stride(down_axis_) * (gv[down_axis_] < 0 ? 1 : -1);  // one cell up
              auto column = [&](bool liquid_below) {  // the interface's height above c's centre, in cells
                auto full = [&](std::ptrdiff_t m) {
                  const double v = f_[c + m * st];
                  return liquid_below ? v >= 1 - kColumnEnd : v <= kColumnEnd;
                };
                auto empty = [&](std::ptrdiff_t m) {
                  const double v = f_[c + m * st];
                  return liquid_below ? v <= kColumnEnd : v >= 1 - kColumnEnd;
                };
                const int kd = full(-1) ? 1 : (full(-2) ? 2 : 0), ku = empty(1) ? 1 : (empty(2) ? 2 : 0);
                if (kd == 0 || ku == 0) return std::numeric_limits<double>::quiet_NaN();
                double sum = 0;
                for (int m = -kd; m <= ku; ++m) sum += liquid_below ? f_[c + m * st] : 1 - f_[c + m * st];
                return sum - kd - 0.5;
              };
              double height = column(true);
              if (std::isnan(height)) height = column(false);
              if (!std::isnan(height)) {
                phi -= std::abs(gv[down_axis_]) * height * g.h(down_axis_);
                interface_phi_[c] = phi;
                return;
              }
            }
            // Otherwise: where the line through the cell's centre along g meets the cell's plane
            // n . xi = alpha (xi: the unit-cube map), x = x_c + s g; on a plane normal to g every
            // point has the same phi. s is kept within the cell's reach.
            double n[3];
            youngs_normal(c, n);
            double along = 0, offset = 0;
            for (int q = 0; q < 3; ++q) {
              along += n[q] * gv[q] / g.h(q);
              offset += 0.5 * n[q];
            }
            if (along != 0) {
              const double alpha = plic::plane_alpha(n[0], n[1], n[2], fc);
              const double reach = g2_ > 0 ? h_max_ / std::sqrt(g2_) : 0.0;
              const double t = std::clamp((alpha - offset) / along, -reach, reach);
              phi += t * g2_;
            }
            interface_phi_[c] = phi;
          });
  g.exchange(interface_phi_);  // the faces on the sub-domain's edges read their neighbours'
}

void FlowSolver::reconstruct(int d) {
  const FluidGrid& g = *grid_;
  std::array<int, 3> lo{g.begin(0), g.begin(1), g.begin(2)}, hi{g.end(0), g.end(1), g.end(2)};
  lo[d] -= 1;
  hi[d] += 1;
  for_box(lo, hi, [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    const double fc = f_[c];
    if (!flow_cells::holds_interface(fc)) return;
    double n[3];
    youngs_normal(c, n);
    if (n[0] == 0 && n[1] == 0 && n[2] == 0) n[d] = 1;  // isolated fragment: any plane will do
    plic_[0][c] = n[0];
    plic_[1][c] = n[1];
    plic_[2][c] = n[2];
    plic_[3][c] = plic::plane_alpha(n[0], n[1], n[2], fc);
  });
}

}  // namespace tessera
