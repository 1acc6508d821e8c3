// SPDX-License-Identifier: MIT
// The coupled run's momentum budget (theory C8): the momentum of the fluid outside the bodies plus
// the bodies' own, P = sum_cells rho (1 - alpha_s) V u + sum_bodies M v, against what gravity and the
// walls gave them since the budget started:
//
//   residual = P(t) - P(0) - sum_steps (m_fluid + m_bodies) g dt - J_walls(fluid) - J_walls(bodies),
//
// m_fluid the fluid mass outside the bodies at each step's start, J_walls(fluid) the flow's wall
// impulses (pressure and viscous stress on the wall faces, FlowSolver::last_wall_impulse) and
// J_walls(bodies) the planar walls' contact impulses on the bodies (DemSolver::wall_impulse). In a
// closed box nothing else acts: the residual is what the discretisation and the coupling's stages
// do not conserve, kept per stage so that a leak is found where it is made. Every sum is exact: the
// same bits on any rank count.
#pragma once
#include "core/vec3.hpp"
#include "fluid/flow_solver.hpp"
#include "solid/dem_solver.hpp"

namespace tessera {

struct MomentumTotals {
  Vec3 fluid, bodies;     // kg m/s
  double fluid_mass = 0;  // outside the bodies, kg
  double body_mass = 0;
};

// Collective: the totals now; solid_fraction is the flow grid's alpha_s (ghosted, as SolidPhase's).
MomentumTotals momentum_totals(const FlowSolver& flow, const std::vector<double>& solid_fraction, const DemSolver& dem);

class MomentumBudget {
 public:
  // The coupled step's stages as the budget sees them: the flow step, the fluid's force and the DEM
  // sub-steps (gravity and the walls act here); the bodies laid out again (the fluid outside them
  // changes its cells); the liquid in the pores (C7: it moves the liquid, so the density); the
  // velocity correction with its exchange (C4a, C4).
  enum Stage { flow_and_bodies, layout, pore_liquid, correction, stages };
  static const char* name(Stage s);
  // Starts the budget from the totals now (the DEM's wall impulse is counted from here on).
  void start(const MomentumTotals& now, DemSolver& dem);
  // After the first stage of a step of dt: gravity's impulse (on the fluid outside the bodies at
  // the step's start and on the bodies) and the walls' (the flow's of the step; the DEM's since the
  // last call) are taken out; what is left is the stage's residual. Collective.
  void after_flow(const MomentumTotals& now, double dt, const Vec3& fluid_gravity, const Vec3& body_gravity,
                  const Vec3& fluid_wall_impulse, const DemSolver& dem);
  // After a stage without outside impulses (the others): its change is its residual.
  void after(Stage stage, const MomentumTotals& now);
  bool started() const { return started_; }
  const MomentumTotals& start_totals() const { return start_; }
  const MomentumTotals& now() const { return now_; }
  Vec3 gravity_impulse() const { return gravity_; }
  Vec3 fluid_wall_impulse() const { return fluid_walls_; }
  Vec3 body_wall_impulse() const { return body_walls_; }
  // What each stage made or lost since the start (kg m/s); their sum is the residual,
  // P(t) - P(0) - the impulses.
  Vec3 stage_residual(Stage s) const { return stage_[s]; }
  Vec3 residual() const { return stage_[flow_and_bodies] + stage_[layout] + stage_[pore_liquid] + stage_[correction]; }

 private:
  bool started_ = false;
  MomentumTotals start_, now_;
  Vec3 gravity_, fluid_walls_, body_walls_;
  Vec3 stage_[stages];
};

}  // namespace tessera
