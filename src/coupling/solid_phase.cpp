// SPDX-License-Identifier: MIT
#include "coupling/solid_phase.hpp"

#include <algorithm>
#include <numeric>

#include "core/errors.hpp"
#include "core/exact_sum.hpp"
#include "solid/rigid_rotation.hpp"

#include <Eigen/Dense>

namespace tessera {

SolidPhase::SolidPhase(const FluidGrid& grid, const DemSolver& dem, double fluid_density, double layout_tolerance,
                       PartialCells partial)
    : grid_(grid), partial_(partial), layout_step_(layout_tolerance * std::min({grid.h(0), grid.h(1), grid.h(2)})) {
  for (int d = 0; d < 3; ++d) inv_h2_ += 1 / (3 * grid.h(d) * grid.h(d)), inv_h_ += 1 / (3 * grid.h(d));
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
  // The lightest body against the denser fluid: below kMinDensityRatio the explicit fluid force
  // (theory C6a) makes the body's motion oscillate and grow.
  double lightest = 1e300;
  for (std::size_t i = 0; i < p.owned; ++i)
    lightest = std::min(lightest, p.mass[i] / dem.shapes()[static_cast<std::size_t>(p.shape[i] - 1)].volume);
  MPI_Allreduce(MPI_IN_PLACE, &lightest, 1, MPI_DOUBLE, MPI_MIN, grid.comm());
  if (lightest < kMinDensityRatio * fluid_density)
    throw InputError("solid.materials", "a body of " + std::to_string(lightest) + " kg/m^3",
                     "bodies at least " + std::to_string(kMinDensityRatio).substr(0, 3) +
                         " times the liquid's density (" + std::to_string(fluid_density) +
                         " kg/m^3): lighter bodies make the explicit fluid force unstable (measured: stable at "
                         "0.25, growing oscillations at 0.1; docs/theory.md C6a)");
  const double half_cell = 0.5 * std::max({grid.h(0), grid.h(1), grid.h(2)});
  for (const ShapeTemplate& t : dem.shapes()) node_reach_.push_back(farthest_node(t));
  for (std::size_t i = 0; i < dem.shapes().size(); ++i) {
    const ShapeTemplate& t = dem.shapes()[i];
    const double reach = node_reach_[i];
    const double ghost_reach = t.bounding_radius + dem.max_radius() + dem.skin();
    if (reach + half_cell > ghost_reach)
      throw InputError("fluid.cells", "cells of " + std::to_string(2 * half_cell) + " m",
                       "cells narrower than 2 (" + std::to_string(ghost_reach) + " - " + std::to_string(reach) +
                           ") m, so that the DEM's ghosts of shape `" + t.name +
                           "` cover every cell its tetrahedra reach");
  }
  // C1: components rounded to `step` turn the body by at most 4 step (the rounding moves the
  // quaternion by at most step, the renormalisation by as much again; the angle is twice that), so
  // a node at distance r moves by at most 4 step r: the largest power of 2 with 4 step r <= the
  // position step keeps every node within it (at most 2^-6, a small turn however small the body).
  for (const double r : node_reach_) {
    turn_step_.push_back(layout_step_ > 0 && r > 0
                             ? std::min(std::exp2(std::floor(std::log2(layout_step_ / (4 * r)))), std::exp2(-6.0))
                             : 0.0);
  }
  alpha_ = grid.make_field();
  solid_mass_ = grid.make_field();
  for (auto& m : solid_momentum_) m = grid.make_field();
}

void SolidPhase::update(const DemSolver& dem) {
  const FluidGrid& g = grid_;
  const ParticleStore& p = dem.particles();
  const auto& shapes = dem.shapes();
  CellRange cells{g.lo(), {g.h(0), g.h(1), g.h(2)}, {g.begin(0), g.begin(1), g.begin(2)},
                  {g.end(0), g.end(1), g.end(2)}};
  // A wall's cells keep what a body pressed into it has beyond it (C1): the body's volume stays on
  // the grid, and the liquid it displaces (C7b) is all there is to fill what it leaves.
  for (int d = 0; d < 3; ++d) {
    if (g.periodic(d)) continue;
    if (g.boundary(d, 0) != BoundaryKind::outflow) cells.first[d] = 0;
    if (g.boundary(d, 1) != BoundaryKind::outflow) cells.last[d] = g.cells()[d] - 1;
  }
  // The box of this rank's cells (reaching beyond a wall as they do): a body whose nodes cannot
  // reach it (most ghosts) has no volume here, and its tetrahedra are not turned or swept.
  Vec3 own_lo, own_hi;
  for (int d = 0; d < 3; ++d) {
    own_lo[d] = g.begin(d) == cells.first[d] ? -HUGE_VAL : g.lo()[d] + g.begin(d) * g.h(d);
    own_hi[d] = g.end(d) - 1 == cells.last[d] ? HUGE_VAL : g.lo()[d] + g.end(d) * g.h(d);
  }
  auto reaches_own_cells = [&](const Vec3& x, double reach) {
    double d2 = 0;
    for (int d = 0; d < 3; ++d) {
      const double out = std::max({own_lo[d] - x[d], x[d] - own_hi[d], 0.0});
      d2 += out * out;
    }
    return d2 <= reach * reach;
  };
  const double cell_volume = g.cell_volume();
  std::fill(alpha_.begin(), alpha_.end(), 0.0);
  std::fill(solid_mass_.begin(), solid_mass_.end(), 0.0);
  // Canonical order: each cell sums its bodies in the same order on any decomposition (C1).
  body_index_.resize(p.size());
  std::iota(body_index_.begin(), body_index_.end(), std::size_t{0});
  std::sort(body_index_.begin(), body_index_.end(), [&](std::size_t a, std::size_t b) { return p.order[a] < p.order[b]; });
  body_first_.assign(1, 0);
  cell_.clear();
  volume_.clear();
  body_volume_ = 0;
  moves_.clear();
  ++generation_;
  std::vector<Vec3> world;
  for (const std::size_t b : body_index_) {
    const ShapeTemplate& t = shapes[static_cast<std::size_t>(p.shape[b] - 1)];
    if (b < p.owned) body_volume_ += t.volume;
    const Pose pose = layout_pose(p.pos(b), {p.q[4 * b], p.q[4 * b + 1], p.q[4 * b + 2], p.q[4 * b + 3]}, p.shape[b]);
    Layout& lay = cache_[p.order[b]];
    lay.generation = generation_;
    if (!lay.valid || lay.pose != pose) {
      ++layouts_;
      const bool moved = lay.valid;  // a body laid out here before: what it left and took (C7)
      if (moved) old_cells_.swap(lay.cells);
      lay.valid = true;
      lay.pose = pose;
      const Quaternion q{pose[3], pose[4], pose[5], pose[6]};
      const Vec3 xb{pose[0], pose[1], pose[2]};
      scratch_.clear();
      // The reach with a margin for the rotation's round-off (1e-9 of it): a node beyond it lies
      // outside the box, and so does every tetrahedron.
      if (reaches_own_cells(xb, node_reach_[static_cast<std::size_t>(p.shape[b] - 1)] * (1 + 1e-9))) {
        world.resize(t.nodes.size());
        for (std::size_t n = 0; n < t.nodes.size(); ++n) world[n] = xb + q.rotate(t.nodes[n]);
        lay_out_body(t, world, cells, raster_, body_polytope_,
                     [&](int i, int j, int k, double v) { scratch_.emplace_back(g.at(i, j, k), v); });
      } else {
        ++layouts_elsewhere_;
      }
      // One entry per cell, its tetrahedra summed in mesh order.
      std::stable_sort(scratch_.begin(), scratch_.end(),
                       [](const auto& a, const auto& c) { return a.first < c.first; });
      lay.cells.clear();
      for (std::size_t e = 0; e < scratch_.size();) {
        const std::size_t c = scratch_[e].first;
        double vol = 0;
        for (; e < scratch_.size() && scratch_[e].first == c; ++e) vol += scratch_[e].second;
        lay.cells.emplace_back(c, vol);
      }
      if (moved) record_move(b, old_cells_, lay.cells);
    }
    const double rho = p.mass[b] / t.volume;
    for (const auto& [c, vol] : lay.cells) {
      cell_.push_back(c);
      volume_.push_back(vol);
      alpha_[c] += vol / cell_volume;
      solid_mass_[c] += rho * vol;
    }
    body_first_.push_back(cell_.size());
  }
  // Bodies no longer here (migrated, or no longer a ghost) leave the cache.
  std::erase_if(cache_, [&](const auto& e) { return e.second.generation != generation_; });
  g.exchange(alpha_);
}

// Both lists are sorted by cell: one entry per cell either holds, new volume minus old.
void SolidPhase::record_move(std::size_t b, const CellVolumes& before, const CellVolumes& after) {
  std::size_t i = 0, j = 0;
  while (i < before.size() || j < after.size()) {
    std::size_t c;
    double dv;
    if (j == after.size() || (i < before.size() && before[i].first < after[j].first))
      c = before[i].first, dv = -before[i].second, ++i;
    else if (i == before.size() || after[j].first < before[i].first)
      c = after[j].first, dv = after[j].second, ++j;
    else
      c = after[j].first, dv = after[j].second - before[i].second, ++i, ++j;
    if (dv != 0) moves_.cell.push_back(c), moves_.dv.push_back(dv);
  }
  moves_.body.push_back(b);
  moves_.first.push_back(moves_.cell.size());
}

// The pose a body is laid out at: its position rounded to multiples of layout_step_ and its
// quaternion's components to multiples of its shape's turn step, renormalised; exact when
// layout_step_ is 0. A function of the pose alone, so every rank holding the body lays it out at
// the same pose.
SolidPhase::Pose SolidPhase::layout_pose(const Vec3& x, const Quaternion& q, int shape) const {
  if (layout_step_ == 0) return {x.x, x.y, x.z, q.w, q.x, q.y, q.z};
  auto snap = [&](double v, double step) { return std::nearbyint(v / step) * step; };
  const double turn = turn_step_[static_cast<std::size_t>(shape - 1)];
  Quaternion r{snap(q.w, turn), snap(q.x, turn), snap(q.y, turn), snap(q.z, turn)};
  const double n = std::sqrt(r.norm2());
  return {snap(x.x, layout_step_), snap(x.y, layout_step_), snap(x.z, layout_step_), r.w / n, r.x / n, r.y / n,
          r.z / n};
}

void SolidPhase::solid_momentum(const DemSolver& dem) {
  const FluidGrid& g = grid_;
  const ParticleStore& p = dem.particles();
  for (auto& m : solid_momentum_) std::fill(m.begin(), m.end(), 0.0);
  for (std::size_t n = 0; n < body_index_.size(); ++n) {
    const std::size_t b = body_index_[n];
    const double rho = p.mass[b] / dem.shapes()[static_cast<std::size_t>(p.shape[b] - 1)].volume;
    const Vec3 xb = p.pos(b), v = p.vel(b), w = p.ang(b);
    for (std::size_t e = body_first_[n]; e < body_first_[n + 1]; ++e) {
      const std::size_t c = cell_[e];
      const auto idx = g.index(c);
      const Vec3 u = v + cross(w, g.centre(idx[0], idx[1], idx[2]) - xb);  // rigid motion at the centre
      const double m = rho * volume_[e];
      for (int d = 0; d < 3; ++d) solid_momentum_[d][c] += m * u[d];
    }
  }
}

// C4a. With U_c = V + w x r_c the body's motion at cell c (r_c = x_c - x_b) and mu_c the reduced
// mass of the cell's fluid (m_f) and the body's share of the cell (m_bc), mu_c = m_f m_bc / (m_f + m_s),
// the correction moves the fluid's momentum by mu_c (U'_c - u_c); the body takes the opposite:
//   M V' = M V + sum mu_c (u_c - U'_c),   I w' = I w + sum mu_c r_c x (u_c - U'_c),
// linear in (V', w'): [(M + S0) 1, -[S3]x; [S3]x, I + S4] (V', w') = (M V + S1, I w + S2), with
// S0 = sum mu, S1 = sum mu u, S2 = sum mu r x u, S3 = sum mu r, S4 = sum mu (|r|^2 1 - r r^T):
// symmetric positive definite. Implicit, so a light body cannot overshoot.
// Per local body the 16 sums of C4a (S0, S1, S2, S3, S4's six entries), ghost shares added to the
// owner's (in loads_, kExchangeWidth per body).
double SolidPhase::cell_rate(const FlowSolver& flow, std::size_t c) const {
  const double a = alpha_[c];
  const double nu = flow.viscosity()[c] / flow.density()[c];
  // C4c: viscous, times 1 + (1.75 / 150) Re for the inertial part (Ergun's ratio; Re = |u - U| h / nu).
  const double inertial = slip_.empty() ? 0.0 : partial_.inertia * slip_[c] / (inv_h_ * nu);
  return partial_.rate * nu * inv_h2_ * a / (1 - a) * (1 + inertial);
}

// `rate`: what the projection's drag (lambda dt capped at kMaxDrag) left of the relaxation
// 1 / (1 + lambda dt): 1 - (1 + D_projection) / (1 + lambda dt).
double SolidPhase::pull(const FlowSolver& flow, std::size_t c, double mf, double ms, double dt) const {
  if (partial_.per_step) return ms / (mf + ms);
  const double lambda_dt = cell_rate(flow, c) * dt;
  return std::max(0.0, lambda_dt - kMaxDrag) / (1 + lambda_dt);
}

const CellDrag* SolidPhase::drag(const FlowSolver& flow, const DemSolver& dem, double dt) {
  if (partial_.per_step) return nullptr;
  const FluidGrid& g = grid_;
  if (drag_.rate.empty()) {
    drag_.rate = g.make_field();
    for (auto& v : drag_.velocity) v = g.make_field();
  }
  solid_momentum(dem);  // the bodies' velocities now
  const auto& rho = flow.density();
  if (partial_.inertia > 0) slip_.assign(alpha_.size(), 0.0);
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) {
        const std::size_t c = g.at(i, j, k);
        const double ms = solid_mass_[c];
        const double mf = rho[c] * g.cell_volume() * std::max(0.0, 1 - alpha_[c]);
        if (ms == 0 || mf == 0) {  // no solid; or covered: the correction gives it the solid's velocity
          drag_.rate[c] = 0;
          for (auto& v : drag_.velocity) v[c] = 0;
          continue;
        }
        if (partial_.inertia > 0) {  // |u - U| at the step's start, for the rate's inertial part
          double s2 = 0;
          for (int d = 0; d < 3; ++d) s2 += std::pow(flow.velocity(d)[c] - solid_momentum_[d][c] / ms, 2);
          slip_[c] = std::sqrt(s2);
        }
        drag_.rate[c] = std::min(cell_rate(flow, c), kMaxDrag / dt);
        for (int d = 0; d < 3; ++d) drag_.velocity[d][c] = solid_momentum_[d][c] / ms;
      }
  g.exchange({&drag_.rate, &drag_.velocity[0], &drag_.velocity[1], &drag_.velocity[2]});
  drag_dt_ = dt;
  return &drag_;
}

void SolidPhase::exchange_sums(const FlowSolver& flow, DemSolver& dem, double dt) {
  const FluidGrid& g = grid_;
  ParticleStore& p = dem.particles();
  const double cell_volume = g.cell_volume();
  const auto& rho_f = flow.density();
  constexpr int kWidth = kExchangeWidth;
  loads_.assign(kWidth * p.size(), 0.0);
  for (std::size_t n = 0; n < body_index_.size(); ++n) {
    const std::size_t b = body_index_[n];
    const double rho = p.mass[b] / dem.shapes()[static_cast<std::size_t>(p.shape[b] - 1)].volume;
    const Vec3 xb = p.pos(b);
    double* acc = &loads_[kWidth * b];
    for (std::size_t e = body_first_[n]; e < body_first_[n + 1]; ++e) {
      const std::size_t c = cell_[e];
      const double mf = rho_f[c] * cell_volume * std::max(0.0, 1 - alpha_[c]);
      if (mf == 0) continue;
      // The fluid's momentum moves by m_f chi (U' - u), chi = pull(); body b's share is m_bc / m_s.
      const double share = rho * volume_[e] / solid_mass_[c];
      double mu = partial_.per_step ? mf * rho * volume_[e] / (mf + solid_mass_[c])
                                    : mf * pull(flow, c, mf, solid_mass_[c], dt) * share;
      const auto idx = g.index(c);
      const Vec3 r = g.centre(idx[0], idx[1], idx[2]) - xb;
      Vec3 u{flow.velocity(0)[c], flow.velocity(1)[c], flow.velocity(2)[c]};
      if (dragged(c)) {
        // C4c's reaction, implicit: the projection pulled the fluid towards the bodies' velocity at
        // the step's start U0 with D = lambda dt; as if towards U' it would have moved by
        // m_f D / (1 + D) (U' - u_D), u_D = U0 + (1 + D) (u - U0). One (mu, u) with both terms.
        const double D = drag_.rate[c] * drag_dt_;
        const double mu_d = mf * D / (1 + D) * share;
        for (int d = 0; d < 3; ++d) {
          const double u0 = drag_.velocity[d][c];
          u[d] = (mu * u[d] + mu_d * (u0 + (1 + D) * (u[d] - u0))) / (mu + mu_d);
        }
        mu += mu_d;
      }
      const Vec3 ru = cross(r, u);
      const double rr = dot(r, r);
      const double add[kWidth] = {mu,          mu * u.x,    mu * u.y,    mu * u.z,         mu * ru.x,        mu * ru.y,
                                  mu * ru.z,   mu * r.x,    mu * r.y,    mu * r.z,         mu * (rr - r.x * r.x),
                                  mu * (rr - r.y * r.y),    mu * (rr - r.z * r.z),         -mu * r.x * r.y,
                                  -mu * r.x * r.z,          -mu * r.y * r.z};
      for (int k = 0; k < kWidth; ++k) acc[k] += add[k];
    }
  }
  if (conserve_)  // C8: the momentum of the fluid each body's new lay-out took (dV > 0) or gave back
    for (std::size_t n = 0; n < moves_.body.size(); ++n) {
      const std::size_t b = moves_.body[n];
      const Vec3 xb = p.pos(b);
      double* acc = &loads_[kWidth * b];
      for (std::size_t e = moves_.first[n]; e < moves_.first[n + 1]; ++e) {
        const std::size_t c = moves_.cell[e];
        const auto idx = g.index(c);
        const Vec3 m = (rho_f[c] * moves_.dv[e]) * Vec3{flow.velocity(0)[c], flow.velocity(1)[c], flow.velocity(2)[c]};
        const Vec3 rm = cross(g.centre(idx[0], idx[1], idx[2]) - xb, m);
        for (int d = 0; d < 3; ++d) acc[1 + d] += m[d], acc[4 + d] += rm[d];
      }
    }
  dem.reverse_add_ghosts(loads_, kWidth);
}

void SolidPhase::exchange_momentum(const FlowSolver& flow, DemSolver& dem, double dt) {
  exchange_sums(flow, dem, dt);
  ParticleStore& p = dem.particles();
  for (std::size_t b = 0; b < p.owned; ++b) {
    const double* a = &loads_[kExchangeWidth * b];
    if (a[0] == 0 && a[1] == 0 && a[2] == 0 && a[3] == 0 && a[4] == 0 && a[5] == 0 && a[6] == 0) continue;
    const ShapeTemplate& t = dem.shapes()[static_cast<std::size_t>(p.shape[b] - 1)];
    const double rho = p.mass[b] / t.volume;
    const Quaternion q{p.q[4 * b], p.q[4 * b + 1], p.q[4 * b + 2], p.q[4 * b + 3]};
    // World inertia R diag(I) R^T.
    Eigen::Matrix3d R;
    for (int k = 0; k < 3; ++k) {
      Vec3 e;
      e[k] = 1;
      const Vec3 col = q.rotate(e);
      for (int i = 0; i < 3; ++i) R(i, k) = col[i];
    }
    const Eigen::Vector3d principal(rho * t.inertia_per_density.x, rho * t.inertia_per_density.y,
                                    rho * t.inertia_per_density.z);
    const Eigen::Matrix3d inertia = R * principal.asDiagonal() * R.transpose();
    const double M = p.mass[b];
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> rhs;
    Eigen::Matrix3d skew;  // [S3]x
    skew << 0, -a[9], a[8], a[9], 0, -a[7], -a[8], a[7], 0;
    Eigen::Matrix3d s4;
    s4 << a[10], a[13], a[14], a[13], a[11], a[15], a[14], a[15], a[12];
    A.block<3, 3>(0, 0) = Eigen::Matrix3d::Identity() * (M + a[0]);
    A.block<3, 3>(0, 3) = -skew;
    A.block<3, 3>(3, 0) = skew;
    A.block<3, 3>(3, 3) = inertia + s4;
    const Eigen::Vector3d v(p.v[3 * b], p.v[3 * b + 1], p.v[3 * b + 2]);
    const Eigen::Vector3d w(p.omega[3 * b], p.omega[3 * b + 1], p.omega[3 * b + 2]);
    rhs.head<3>() = M * v + Eigen::Vector3d(a[1], a[2], a[3]);
    rhs.tail<3>() = inertia * w + Eigen::Vector3d(a[4], a[5], a[6]);
    const Eigen::Matrix<double, 6, 1> x = A.ldlt().solve(rhs);
    for (int k = 0; k < 3; ++k) p.v[3 * b + k] = x[k], p.omega[3 * b + k] = x[3 + k];
  }
  dem.refresh_ghosts();
}

void SolidPhase::held_exchange(const FlowSolver& flow, DemSolver& dem, double dt) {
  exchange_sums(flow, dem, dt);
  ParticleStore& p = dem.particles();
  for (std::size_t b = 0; b < p.owned; ++b)
    for (int k = 0; k < 3; ++k) {
      p.f_ext[3 * b + k] += loads_[kExchangeWidth * b + 1 + k] / dt;
      p.t_ext[3 * b + k] += loads_[kExchangeWidth * b + 4 + k] / dt;
    }
}

void SolidPhase::fluid_loads(const FlowSolver& flow, DemSolver& dem, double dt) {
  const FluidGrid& g = grid_;
  ParticleStore& p = dem.particles();
  const bool viscous = !flow.stress_divergence(0).empty();
  const bool advection = conserve_ && dt > 0 && !flow.advection_change(0).empty();
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
      if (advection)
        for (int d = 0; d < 3; ++d) density[d] += flow.advection_change(d)[c] / dt;
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

void SolidPhase::correct_velocity(FlowSolver& flow, const DemSolver& dem, double dt) {
  solid_momentum(dem);  // from the bodies' velocities now (after the DEM and the exchange)
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
        if (partial_.per_step || mf == 0) {  // the mass average (C4); a covered cell: the solid's velocity
          for (int d = 0; d < 3; ++d) (*u[d])[c] = (mf * (*u[d])[c] + solid_momentum_[d][c]) / (mf + ms);
          continue;
        }
        // C4c: the projection's drag moved to the bodies' velocity now (U' - U0), then the rest of
        // the relaxation beyond the projection's cap.
        const double chi = pull(flow, c, mf, ms, dt);
        const double D = dragged(c) ? drag_.rate[c] * drag_dt_ : 0.0;
        for (int d = 0; d < 3; ++d) {
          const double U = solid_momentum_[d][c] / ms;
          const double du = D > 0 ? D / (1 + D) * (U - drag_.velocity[d][c]) : 0.0;
          (*u[d])[c] += du + chi * (U - (*u[d])[c]);
        }
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
        const std::size_t c = g.at(i, j, k);
        const double a = alpha_[c];
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
