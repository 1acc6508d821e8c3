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

const char* MomentumBudget::name(Stage s) {
  switch (s) {
    case flow_and_bodies: return "flow_and_bodies";
    case layout: return "layout";
    case pore_liquid: return "pore_liquid";
    case correction: return "correction";
    default: return "?";
  }
}

void MomentumBudget::start(const MomentumTotals& now, DemSolver& dem) {
  started_ = true;
  start_ = now_ = now;
  gravity_ = fluid_walls_ = body_walls_ = Vec3{};
  for (Vec3& r : stage_) r = Vec3{};
  dem.track_wall_impulse(true);
}

void MomentumBudget::after_flow(const MomentumTotals& now, double dt, const Vec3& fluid_gravity, const Vec3& body_gravity,
                                const Vec3& fluid_wall_impulse, const DemSolver& dem) {
  const Vec3 gravity = (now_.fluid_mass * dt) * fluid_gravity + (now_.body_mass * dt) * body_gravity;
  const Vec3 body_walls = dem.wall_impulse();
  stage_[flow_and_bodies] += (now.fluid + now.bodies) - (now_.fluid + now_.bodies) - gravity - fluid_wall_impulse -
                             (body_walls - body_walls_);
  gravity_ += gravity;
  fluid_walls_ += fluid_wall_impulse;
  body_walls_ = body_walls;
  now_ = now;
}

void MomentumBudget::after(Stage stage, const MomentumTotals& now) {
  stage_[stage] += (now.fluid + now.bodies) - (now_.fluid + now_.bodies);
  now_ = now;
}

}  // namespace tessera
