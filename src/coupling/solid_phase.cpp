// SPDX-License-Identifier: MIT
#include "coupling/solid_phase.hpp"

#include <algorithm>
#include <numeric>

#include "core/errors.hpp"
#include "core/exact_sum.hpp"
#include "solid/rigid_rotation.hpp"

namespace tessera {

SolidPhase::SolidPhase(const FluidGrid& grid, const DemSolver& dem) : grid_(grid) {
  const ParticleStore& p = dem.particles();
  int spheres = 0;
  for (std::size_t i = 0; i < p.owned; ++i) spheres |= p.shape[i] == 0;
  MPI_Allreduce(MPI_IN_PLACE, &spheres, 1, MPI_INT, MPI_MAX, grid.comm());
  if (spheres)
    throw InputError("solid.bodies", "sphere bodies",
                     "bodies made of tetrahedra (a shape template; a sphere is `spheroid` with equal semi-axes)");
  for (int d = 0; d < 3; ++d)
    if (grid.periodic(d))
      throw InputError("fluid.boundaries", "periodic", "walls or outflow: coupled bodies do not cross periodic sides");
  const double half_cell = 0.5 * std::max({grid.h(0), grid.h(1), grid.h(2)});
  for (const ShapeTemplate& t : dem.shapes()) {
    double reach = 0;
    for (const Vec3& n : t.nodes) reach = std::max(reach, norm(n));
    const double ghost_reach = t.bounding_radius + dem.max_radius() + dem.skin();
    if (reach + half_cell > ghost_reach)
      throw InputError("fluid.cells", "cells of " + std::to_string(2 * half_cell) + " m",
                       "cells narrower than 2 (" + std::to_string(ghost_reach) + " - " + std::to_string(reach) +
                           ") m, so that the DEM's ghosts of shape `" + t.name +
                           "` cover every cell its tetrahedra reach");
  }
  alpha_ = grid.make_field();
  solid_mass_ = grid.make_field();
  for (auto& m : solid_momentum_) m = grid.make_field();
}

void SolidPhase::update(const DemSolver& dem) {
  const FluidGrid& g = grid_;
  const ParticleStore& p = dem.particles();
  const auto& shapes = dem.shapes();
  const CellRange cells{g.lo(), {g.h(0), g.h(1), g.h(2)}, {g.begin(0), g.begin(1), g.begin(2)},
                        {g.end(0), g.end(1), g.end(2)}};
  const double cell_volume = g.cell_volume();
  std::fill(alpha_.begin(), alpha_.end(), 0.0);
  std::fill(solid_mass_.begin(), solid_mass_.end(), 0.0);
  for (auto& m : solid_momentum_) std::fill(m.begin(), m.end(), 0.0);
  // Canonical order: each cell sums its bodies in the same order on any decomposition (C1).
  body_index_.resize(p.size());
  std::iota(body_index_.begin(), body_index_.end(), std::size_t{0});
  std::sort(body_index_.begin(), body_index_.end(), [&](std::size_t a, std::size_t b) { return p.order[a] < p.order[b]; });
  body_first_.assign(1, 0);
  cell_.clear();
  volume_.clear();
  body_volume_ = 0;
  std::vector<Vec3> world;
  for (const std::size_t b : body_index_) {
    const ShapeTemplate& t = shapes[static_cast<std::size_t>(p.shape[b] - 1)];
    if (b < p.owned) body_volume_ += t.volume;
    const Quaternion q{p.q[4 * b], p.q[4 * b + 1], p.q[4 * b + 2], p.q[4 * b + 3]};
    const Vec3 xb = p.pos(b);
    world.resize(t.nodes.size());
    for (std::size_t n = 0; n < t.nodes.size(); ++n) world[n] = xb + q.rotate(t.nodes[n]);
    scratch_.clear();
    for (const auto& tet : t.tetrahedra)
      raster_.overlaps(Tet{world[tet[0]], world[tet[1]], world[tet[2]], world[tet[3]]}, cells,
                       [&](int i, int j, int k, double v) { scratch_.emplace_back(g.at(i, j, k), v); });
    // One entry per cell, its tetrahedra summed in mesh order.
    std::stable_sort(scratch_.begin(), scratch_.end(), [](const auto& a, const auto& c) { return a.first < c.first; });
    const double rho = p.mass[b] / t.volume;
    const Vec3 v = p.vel(b), w = p.ang(b);
    for (std::size_t e = 0; e < scratch_.size();) {
      const std::size_t c = scratch_[e].first;
      double vol = 0;
      for (; e < scratch_.size() && scratch_[e].first == c; ++e) vol += scratch_[e].second;
      cell_.push_back(c);
      volume_.push_back(vol);
      const auto idx = g.index(c);
      const Vec3 u = v + cross(w, g.centre(idx[0], idx[1], idx[2]) - xb);  // rigid motion at the centre
      alpha_[c] += vol / cell_volume;
      solid_mass_[c] += rho * vol;
      for (int d = 0; d < 3; ++d) solid_momentum_[d][c] += rho * vol * u[d];
    }
    body_first_.push_back(cell_.size());
  }
  g.exchange(alpha_);
}

void SolidPhase::fluid_loads(const FlowSolver& flow, DemSolver& dem) {
  const FluidGrid& g = grid_;
  ParticleStore& p = dem.particles();
  const bool viscous = !flow.stress_divergence(0).empty();
  loads_.assign(6 * p.size(), 0.0);
  for (std::size_t n = 0; n < body_index_.size(); ++n) {
    const std::size_t b = body_index_[n];
    const Vec3 xb = p.pos(b);
    Vec3 force, moment;
    for (std::size_t e = body_first_[n]; e < body_first_[n + 1]; ++e) {
      const std::size_t c = cell_[e];
      const auto idx = g.index(c);
      Vec3 density = flow.pressure_force(idx[0], idx[1], idx[2]);  // N/m^3
      if (viscous)
        for (int d = 0; d < 3; ++d) density[d] += flow.stress_divergence(d)[c];
      const Vec3 f = density * volume_[e];
      force += f;
      moment += cross(g.centre(idx[0], idx[1], idx[2]) - xb, f);
    }
    force.store(&loads_[6 * b]);
    moment.store(&loads_[6 * b + 3]);
  }
  dem.reverse_add_ghosts(loads_, 6);
  for (std::size_t b = 0; b < p.owned; ++b)
    for (int d = 0; d < 3; ++d) {
      p.f_ext[3 * b + d] = loads_[6 * b + d];
      p.t_ext[3 * b + d] = loads_[6 * b + 3 + d];
    }
}

void SolidPhase::correct_velocity(FlowSolver& flow) const {
  const FluidGrid& g = grid_;
  const double cell_volume = g.cell_volume();
  const auto& rho = flow.density();
  std::array<std::vector<double>*, 3> u{&flow.mutable_velocity(0), &flow.mutable_velocity(1), &flow.mutable_velocity(2)};
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) {
        const std::size_t c = g.at(i, j, k);
        const double ms = solid_mass_[c];
        if (ms == 0) continue;
        const double mf = rho[c] * cell_volume * std::max(0.0, 1 - alpha_[c]);
        for (int d = 0; d < 3; ++d) (*u[d])[c] = (mf * (*u[d])[c] + solid_momentum_[d][c]) / (mf + ms);
      }
  flow.velocity_changed();
}

SolidPhaseStats SolidPhase::stats() const {
  const FluidGrid& g = grid_;
  SolidPhaseStats s;
  ExactSum sums[2];
  double amax = 0;
  long covered = 0;
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) {
        const double a = alpha_[g.at(i, j, k)];
        sums[0].add(a * g.cell_volume());
        amax = std::max(amax, a);
        covered += a > 0;
      }
  sums[1].add(body_volume_);
  ExactSum::all_reduce(sums, g.comm());
  s.solid_volume = sums[0].value();
  s.body_volume = sums[1].value();
  s.max_fraction = g.reduce_max(amax);
  MPI_Allreduce(&covered, &s.covered_cells, 1, MPI_LONG, MPI_SUM, g.comm());
  return s;
}

}  // namespace tessera
