// SPDX-License-Identifier: MIT
#include "coupling/coupled_step.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace tessera {

CouplingSettings CouplingSettings::from_config(const ConfigNode& c) {
  CouplingSettings s;
  // Unknown keys are reported by Config::check_unused.
  if (c.has("substeps")) s.substeps = static_cast<int>(c.integer("substeps", 1, 1'000'000));
  s.fluid_force = c.flag("fluid_force", true);
  s.liquid_in_pores = c.flag("liquid_in_pores", true);
  s.fixed_bodies = c.choice("bodies", {"moving", "fixed"}, "moving") == "fixed";
  s.momentum_budget = c.flag("momentum_budget", false);
  s.conserve_momentum = c.flag("conserve_momentum", false);
  if (s.momentum_budget && (s.fixed_bodies || !s.fluid_force))
    throw InputError("coupling.momentum_budget", "true",
                     "the budget needs moving bodies that feel the fluid (bodies: moving, fluid_force: true)");
  s.layout_tolerance = c.real("layout_tolerance", Dim::none, Range::closed(0, 0.25), s.layout_tolerance);
  s.partial.per_step = c.choice("partial_cells", {"step", "rate"}, "step") == "step";
  s.partial.rate = c.real("partial_cell_rate", Dim::none, Range::positive(), s.partial.rate);
  s.partial.inertia = c.real("partial_cell_inertia", Dim::none, Range::closed(0, 1e6), s.partial.inertia);
  return s;
}

CoupledSolver::CoupledSolver(FlowSolver& flow, DemSolver& dem, CouplingSettings settings)
    : flow_(flow), dem_(dem), settings_(settings), solid_(flow.grid(), dem, std::max(flow.settings().liquid.density, flow.settings().gas.density),
             settings.layout_tolerance, settings.partial), liquid_(flow.grid()), dem_stable_dt_(dem.dt()) {
  dem_.use_external_loads(settings_.fluid_force && !settings_.fixed_bodies);
  flow_.keep_stress_divergence(loads_computed());
  const bool conserve = settings_.conserve_momentum && settings_.fluid_force && !settings_.fixed_bodies;
  flow_.keep_advection_change(conserve);
  solid_.conserve_momentum(conserve);
}

void CoupledSolver::start(bool fresh) {
  if (settings_.fixed_bodies) {  // held at rest, ghost copies too
    ParticleStore& p = dem_.particles();
    std::fill(p.v.begin(), p.v.end(), 0.0);
    std::fill(p.omega.begin(), p.omega.end(), 0.0);
  }
  solid_.update(dem_);
  if (!fresh) {
    if (settings_.liquid_in_pores) liquid_.resume(solid_.fraction());
    return;
  }
  if (settings_.liquid_in_pores) {
    liquid_.start(flow_, solid_.fraction());
    liquid_.settle(flow_, solid_.fraction());
  }
  solid_.correct_velocity(flow_, dem_, 0.0);
}

void CoupledSolver::take_over(const CoupledSolver& old) {
  timers_ = old.timers_;
  budget_ = old.budget_;
  solid_.count_layouts(old.solid_.layouts_computed(), old.solid_.layouts_elsewhere());
}

int CoupledSolver::substeps_for(double dt) const {
  if (settings_.substeps) return *settings_.substeps;
  // The least L with dt / L <= the DEM's stable step (C5); a relative 1e-12 slack so that a flow
  // step of exactly L DEM steps is not rounded up to L + 1.
  return std::max(1, static_cast<int>(std::ceil(dt / dem_stable_dt_ * (1 - 1e-12))));
}

CoupledStepStats CoupledSolver::step(double dt) {
  CoupledStepStats st;
  {
    auto t = timers_.scope("flow");
    if (settings_.liquid_in_pores) liquid_.before_flow(flow_);
    flow_.set_cell_drag(solid_.drag(flow_, dem_, dt));  // C4c: partly covered cells, in the projection
    st.flow = flow_.advance(dt);
    if (settings_.liquid_in_pores) liquid_.after_flow(flow_);
  }
  if (loads_computed()) {
    auto t = timers_.scope("fluid_force");
    solid_.fluid_loads(flow_, dem_, dt);
  }
  if (settings_.fixed_bodies) {
    dem_.set_clock(dem_.time() + dt, dem_.steps());  // held: the clock only (output times)
  } else {
    st.substeps = substeps_for(dt);
    st.dem_dt = dt / st.substeps;
    auto t = timers_.scope("dem_substeps");
    dem_.advance(st.dem_dt, st.substeps);
  }
  const bool budget = budget_.started();
  if (budget)
    budget_.after_flow(totals(), dt, flow_.settings().gravity, dem_.gravity(), flow_.last_wall_impulse(), dem_);
  {
    auto t = timers_.scope("solid_fraction");
    solid_.update(dem_);
  }
  if (budget) budget_.after(MomentumBudget::layout, totals());
  if (settings_.liquid_in_pores) {
    auto t = timers_.scope("pore_liquid");
    liquid_.displace(solid_.moves(), dem_.particles().size(), [&](std::vector<double>& sums) {
      dem_.reverse_add_ghosts(sums, 2);
      dem_.forward_to_ghosts(sums, 2);
    });
    st.liquid = liquid_.settle(flow_, solid_.fraction());
  }
  if (budget) budget_.after(MomentumBudget::pore_liquid, totals());
  {
    auto t = timers_.scope("correction");
    if (settings_.fixed_bodies) {
      solid_.held_exchange(flow_, dem_, dt);  // reported with C3's load (C4b)
      const ParticleStore& p = dem_.particles();
      held_impulse_.resize(6 * p.owned, 0.0);
      for (std::size_t b = 0; b < p.owned; ++b)
        for (int k = 0; k < 3; ++k) {
          held_impulse_[6 * b + k] += p.f_ext[3 * b + k] * dt;
          held_impulse_[6 * b + 3 + k] += p.t_ext[3 * b + k] * dt;
        }
      held_time_ += dt;
    } else if (settings_.fluid_force) {
      solid_.exchange_momentum(flow_, dem_, dt);
    }
    solid_.correct_velocity(flow_, dem_, dt);
  }
  if (budget) budget_.after(MomentumBudget::correction, totals());
  return st;
}

void CoupledSolver::start_momentum_budget() {
  if (settings_.fixed_bodies || !settings_.fluid_force)
    throw InputError("coupling.momentum_budget", "true",
                     "the budget needs moving bodies that feel the fluid (bodies: moving, fluid_force: true)");
  budget_.start(totals(), dem_);
}

MomentumTotals CoupledSolver::totals() const { return momentum_totals(flow_, solid_.fraction(), dem_); }

void CoupledSolver::average_held_loads() {
  if (!settings_.fixed_bodies || held_time_ == 0) return;
  ParticleStore& p = dem_.particles();  // held bodies never move, so their order never changes
  for (std::size_t b = 0; b < p.owned; ++b)
    for (int k = 0; k < 3; ++k) {
      p.f_ext[3 * b + k] = held_impulse_[6 * b + k] / held_time_;
      p.t_ext[3 * b + k] = held_impulse_[6 * b + 3 + k] / held_time_;
    }
  std::fill(held_impulse_.begin(), held_impulse_.end(), 0.0);
  held_time_ = 0;
}

}  // namespace tessera
