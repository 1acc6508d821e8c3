// SPDX-License-Identifier: MIT
// The coupled run's momentum budget (theory C8): the momentum of the fluid outside the bodies plus
// the bodies' own, against what gravity and the walls gave them since the budget started,
//
//   residual = P(t) - P(0) - sum_steps (m_fluid + m_bodies) g dt - J_walls(fluid) - J_walls(bodies),
//
// P = sum_cells rho (1 - alpha_s) V u + sum_bodies M v, m_fluid the fluid mass outside the bodies (the
// mean of the step's two ends), J_walls(fluid) the flow's wall impulses (pressure and viscous stress
// on the wall faces, FlowSolver::last_wall_impulse) and J_walls(bodies) the planar walls' contact
// impulses on the bodies (DemSolver::wall_impulse). In a closed box nothing else acts: what is left
// is what the discretisation and the coupling's stages do not conserve. Every sum is exact: the
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
  // Starts the budget from the totals now (the DEM's wall impulse is counted from here on).
  void start(const MomentumTotals& now, DemSolver& dem);
  // After a step of dt: the totals at its end and the flow's wall impulse of the step (collective:
  // reads the DEM's wall impulse).
  void add_step(const MomentumTotals& now, double dt, const Vec3& fluid_gravity, const Vec3& body_gravity,
                const Vec3& fluid_wall_impulse, const DemSolver& dem);
  bool started() const { return started_; }
  const MomentumTotals& start_totals() const { return start_; }
  const MomentumTotals& now() const { return now_; }
  Vec3 gravity_impulse() const { return gravity_; }
  Vec3 fluid_wall_impulse() const { return fluid_walls_; }
  Vec3 body_wall_impulse() const { return body_walls_; }
  // P(t) - P(0) - the impulses (kg m/s).
  Vec3 residual() const;

 private:
  bool started_ = false;
  MomentumTotals start_, now_;
  Vec3 gravity_, fluid_walls_, body_walls_;
};

}  // namespace tessera
