// SPDX-License-Identifier: MIT
#include "coupling/momentum_budget.hpp"

#include <algorithm>
#include <array>

#include "core/exact_sum.hpp"

namespace tessera {

MomentumTotals momentum_totals(const FlowSolver& flow, const std::vector<double>& solid_fraction, const DemSolver& dem) {
  const FluidGrid& g = flow.grid();
  const double volume = g.h(0) * g.h(1) * g.h(2);
  // fluid x, y, z, fluid mass, bodies x, y, z, body mass
  std::array<ExactSum, 8> sums;
  const std::vector<double>& rho = flow.density();
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) {
        const std::size_t c = g.at(i, j, k);
        const double m = rho[c] * (1 - std::min(solid_fraction[c], 1.0)) * volume;
        for (int d = 0; d < 3; ++d) sums[d] += m * flow.velocity(d)[c];
        sums[3] += m;
      }
  const ParticleStore& p = dem.particles();
  for (std::size_t b = 0; b < p.owned; ++b) {
    for (int d = 0; d < 3; ++d) sums[4 + d] += p.mass[b] * p.v[3 * b + d];
    sums[7] += p.mass[b];
  }
  ExactSum::all_reduce(sums, g.comm());
  MomentumTotals t;
  t.fluid = {sums[0].value(), sums[1].value(), sums[2].value()};
  t.fluid_mass = sums[3].value();
  t.bodies = {sums[4].value(), sums[5].value(), sums[6].value()};
  t.body_mass = sums[7].value();
  return t;
}

void MomentumBudget::start(const MomentumTotals& now, DemSolver& dem) {
  started_ = true;
  start_ = now_ = now;
  gravity_ = fluid_walls_ = body_walls_ = Vec3{};
  dem.track_wall_impulse(true);
}

void MomentumBudget::add_step(const MomentumTotals& now, double dt, const Vec3& fluid_gravity, const Vec3& body_gravity,
                              const Vec3& fluid_wall_impulse, const DemSolver& dem) {
  // The fluid outside the bodies changes its mass as the bodies move (and its density as the
  // liquid does): the mean of the step's two ends.
  gravity_ += (0.5 * (now_.fluid_mass + now.fluid_mass) * dt) * fluid_gravity +
              (0.5 * (now_.body_mass + now.body_mass) * dt) * body_gravity;
  fluid_walls_ += fluid_wall_impulse;
  body_walls_ = dem.wall_impulse();
  now_ = now;
}

Vec3 MomentumBudget::residual() const {
  return (now_.fluid + now_.bodies) - (start_.fluid + start_.bodies) - gravity_ - fluid_walls_ - body_walls_;
}

}  // namespace tessera
