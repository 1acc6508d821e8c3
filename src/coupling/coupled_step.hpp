// SPDX-License-Identifier: MIT
// One coupled flow-DEM step (MICS, drop-impact seed Fig. 1; theory C1-C6), as named stages with one
// timer each:
//
//   flow            the air/water flow over dt, the bodies' cells holding the corrected velocity
//                   of the last step (FlowSolver::advance)
//   fluid_force     force and moment of the flow on each body from the cells its tetrahedra cover,
//                   ghost shares sent back to the owner (SolidPhase::fluid_loads, C3)
//   dem_substeps    L DEM steps of dt / L with that load held (DemSolver::advance, C5)
//   solid_fraction  the moved tetrahedra laid over the cells again (SolidPhase::update, C1-C2)
//   pore_liquid     the liquid kept in the cells' fluid part: what the flow carried across faces
//                   (recorded around the flow stage) and what the moved bodies displaced (PoreLiquid, C7)
//   correction      cell velocities move to the bodies' (C4; partly covered cells: C4c)
//
// With `coupling.bodies: fixed` the DEM does not run (its clock follows the flow's): fluid_force
// still records each body's load, the correction holds the bodies' cells at rest.
//
// The flow's pressure equation runs over the whole grid with the fluid's density in every cell:
// inside a body the fluid is a virtual one that moves with it (docs/design.md, "Coupled step", says
// why not the mixture density).
#pragma once
#include <optional>
#include <vector>

#include "core/config.hpp"
#include "coupling/momentum_budget.hpp"
#include "coupling/pore_liquid.hpp"
#include "coupling/solid_phase.hpp"

namespace tessera {

struct CouplingSettings {
  std::optional<int> substeps;  // L; none: the least L with dt / L <= the DEM's own stable step
  bool fluid_force = true;      // off: the bodies move the flow, the flow does not push them
  double layout_tolerance = 0.01;  // fraction of the cell: lay-outs reused within it (SolidPhase)
  // The liquid kept in the cells' fluid part (C7). Off: the liquid fraction is advected over whole
  // cells, the bodies' insides included (the settling sphere, where C7 is not yet right: theory C7).
  bool liquid_in_pores = true;
  // `bodies: fixed`: the bodies stay where they are, at rest (a fixed bed or array that the flow
  // passes through): no DEM sub-steps and no exchange C4a; the fluid's force on each body (C3) is
  // still computed and reported, not applied. `moving` (the default): the coupled step as above.
  bool fixed_bodies = false;
  // A partly covered cell: `partial_cells: step` (the default: the seed's mass average every step)
  // or `rate` (dragged towards the solid's velocity at the rate `partial_cell_rate` nu alpha /
  // ((1 - alpha) h^2), implicit in the projection: the same on any step). Theory C4c.
  PartialCells partial;
  // `momentum_budget: true`: the scene keeps the momentum budget of fluid and bodies (C8) from its
  // start (or restart) and reports it in summary.json (four passes over the cells per step).
  bool momentum_budget = false;
  // `conserve_momentum: true`: the bodies take MICS's two momentum leaks (C8), the advection's change
  // of their virtual fluid and the momentum of the fluid their lay-out displaces. Off by default:
  // the seed's scheme.
  bool conserve_momentum = false;
  static CouplingSettings from_config(const ConfigNode& coupling);
};

struct CoupledStepStats {
  FlowStepStats flow;
  int substeps = 0;
  double dem_dt = 0;
  PoreLiquidStats liquid;
};

class CoupledSolver {
 public:
  // Both solvers set up (DemSolver::setup, FlowSolver::initialize); keeps references.
  CoupledSolver(FlowSolver& flow, DemSolver& dem, CouplingSettings settings);

  // The solid phase of the current bodies. `fresh`: also corrects the cell velocities (C4) and puts
  // the liquid in the cells' fluid part (C7); a restart's velocities were corrected before they were
  // saved, and its liquid content is read (mutable_liquid) before or after this call.
  void start(bool fresh = true);
  // After the cut planes moved (issue 19): this solver, made on the repartitioned grid with the
  // rebalanced bodies, takes over the run's record from the one it replaces (timers, momentum
  // budget, lay-out count). Then start(false), as a restart.
  void take_over(const CoupledSolver& old);
  CoupledStepStats step(double dt);
  // L for a flow step dt.
  int substeps_for(double dt) const;
  double dem_stable_dt() const { return dem_stable_dt_; }

  const SolidPhase& solid() const { return solid_; }
  const PoreLiquid& liquid() const { return liquid_; }
  bool liquid_in_pores() const { return settings_.liquid_in_pores; }
  bool fixed_bodies() const { return settings_.fixed_bodies; }
  // The fluid's force on the bodies (C3) is computed each step: with `fluid_force` or fixed bodies.
  bool loads_computed() const { return settings_.fluid_force || settings_.fixed_bodies; }
  // Fixed bodies: their loads (C3 + C4b) become the mean over the steps since the last call (the
  // impulse over the time), and the sums restart; nothing when no step was made since. The load of
  // one step is not a steady body's force when dt changes: the velocity C4 leaves in a partly
  // covered cell scales with the step before (theory C4b).
  void average_held_loads();
  // The momentum budget of fluid and bodies (C8), from now on, updated at four stages of every
  // step (collective; four passes over the cells per step, so off unless asked for). Moving bodies
  // with the fluid force only: held bodies' support and one-way coupling are outside it.
  void start_momentum_budget();
  const MomentumBudget& momentum_budget() const { return budget_; }
  PoreLiquid& mutable_liquid() { return liquid_; }
  FlowSolver& flow() { return flow_; }
  DemSolver& dem() { return dem_; }
  PhaseTimers& timers() { return timers_; }

 private:
  MomentumTotals totals() const;  // collective (the budget's)
  FlowSolver& flow_;
  DemSolver& dem_;
  CouplingSettings settings_;
  SolidPhase solid_;
  PoreLiquid liquid_;
  double dem_stable_dt_ = 0;
  PhaseTimers timers_;
  std::vector<double> held_impulse_;  // fixed bodies: 6 per owned body, since average_held_loads
  double held_time_ = 0;
  MomentumBudget budget_;
};

}  // namespace tessera
