// SPDX-License-Identifier: MIT
// Incompressible two-phase (liquid/gas) flow with a sharp volume-of-fluid interface on a collocated
// Cartesian grid (docs/theory.md F1-F12; drop-impact seed eqs. 1-3):
//
//   d(rho)/dt + div(rho u) = 0,  div u = 0,
//   d(rho u)/dt + div(rho u u) = -grad p + div(mu (grad u + grad u^T)) + rho g,
//   rho = rho_g + (rho_l - rho_g) f,  mu = mu_g + (mu_l - mu_g) f.
//
// One step (advance):
//   1. advect   direction-split geometric VOF (PLIC, Youngs normals; Weymouth & Yue 2010 dilatation
//               term, so liquid volume is conserved to round-off and 0 <= f <= 1 for CFL <= 1/2),
//               and in the same sweeps the momentum rho u, with the mass fluxes of the VOF
//               fluxes (rho_g, rho_l on the gas and liquid parts of each face flux) and a van Leer
//               limited upwind velocity: density and momentum move together, so a uniform velocity
//               is kept exactly at any density ratio (F3-F8).
//   2. viscous  explicit variable-viscosity stress (full grad u + grad u^T) on the advected velocity.
//   3. project  face velocities u*_f = mean of the two cells + dt b_f, b_f = g_f, or across a
//               density jump gravity balanced at the interface (F10b); Poisson for p (F9,
//               pressure_poisson.hpp); u_f = u*_f + dt a_f with a_f = b_f - grad_f p / rho_f;
//               cell velocities gain the mean of their two face accelerations per direction.
//               Rest is exact: a_f = 0 on every face for any interface normal to g (F10, F10b).
// The face velocities satisfy discrete continuity to the Poisson tolerance and carry the next
// step's VOF and momentum fluxes (the collocated MICS / approximate-projection scheme).
//
// A cell drag (the coupling's partly covered cells, theory C4c) enters step 3 implicitly: per cell a
// rate lambda and a velocity U it pulls towards, D = lambda dt,
//   u_c = (u*_c + D_c U_c + dt a_c) / (1 + D_c),  u_f = (u*_f + D_f U_f + dt a_f) / (1 + D_f),
// the Poisson equation taking the face coefficients 1 / (rho_f (1 + D_f)) (rho (1 + D) in each cell,
// its faces the mean of the two). The face accelerations a_f stay the pressure's and gravity's.
// At a steady state lambda (u - U) = a + the viscous stage's: the same on any step.
//
// Surface tension is not in the seeds' scenes: its place is a face force added to a_f before the
// projection (step 3), where the gravity term enters.
#pragma once
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/decomposition.hpp"
#include "core/exact_sum.hpp"
#include "core/timers.hpp"
#include "fluid/fluid_grid.hpp"
#include "fluid/pressure_poisson.hpp"

namespace tessera {

// The flow's input from a solid phase (theory C4c): ghosted cell fields, the drag rate lambda (1/s;
// 0: none) and the velocity it pulls towards.
struct CellDrag {
  std::vector<double> rate;
  std::array<std::vector<double>, 3> velocity;
};

struct FluidPhase {
  double density = 1000;    // kg/m^3
  double viscosity = 1e-3;  // Pa s
};

struct FlowSettings {
  std::array<int, 3> cells{16, 16, 16};
  std::array<std::array<BoundaryKind, 2>, 3> boundaries{};  // default no-slip everywhere
  FluidPhase liquid{1000, 1.0e-3}, gas{1.0, 1.8e-5};
  Vec3 gravity{0, 0, -9.81};
  double cfl = 0.45;            // advective: max |u_d| dt / h_d over directions (<= 0.5 for WY)
  double viscous_number = 0.4;  // dt <= viscous_number / (2 nu sum 1/h_d^2) (1 = stability limit)
  double gravity_number = 0.5;  // dt <= gravity_number sqrt(h_min / |g|)
  double dt_max = 1e-2, dt_min = 1e-12;
  double dt_growth = 1.1;  // dt grows at most by this factor per step
  // Stress on no-slip walls. `laminar`: mu u / (h/2) from the cell centre, which is the resolved
  // stress only when the wall layer spans cells. `spalding`: the stress of Spalding's (1961) law of
  // the wall at the cell centre (kappa 0.41, B 5.2), for wall layers thinner than a cell; it equals
  // the laminar one for y+ below about 3, and is applied implicitly (theory F9b).
  enum class WallModel { laminar, spalding };
  WallModel wall_model = WallModel::laminar;
  // `fluid.energy_budget: true`: each step also measures the energy every stage changes (F12a):
  // FlowSolver::energy_budget() and the per-cell `advection_energy_source`. Off by default (two
  // extra reductions and field passes a stage).
  bool energy_budget = false;
  PoissonSettings poisson;

  // From the case's `fluid` section (every key checked; errors name the key).
  static FlowSettings from_config(const ConfigNode& fluid);
  // Its parts that lay out the pressure's multigrid (`tessera balance` reads these alone): the
  // boundaries (`boundaries`) and the Poisson solver (`poisson`).
  static std::array<std::array<BoundaryKind, 2>, 3> boundaries_from_config(const ConfigNode& fluid);
  static PoissonSettings poisson_from_config(const ConfigNode& fluid);
};

struct FlowStepStats {
  double dt = 0;
  std::string dt_limit;  // "cfl", "viscous", "gravity", "max", "growth", "output"
  PoissonStats poisson;
};

// Spalding's law of the wall: for a speed U at distance y from the wall in a fluid of kinematic
// viscosity nu, the factor tau_w y / (mu U) = y+ / u+ (>= 1; 1 in the viscous sublayer).
double spalding_stress_factor(double speed, double y, double nu);

class FlowSolver {
 public:
  FlowSolver(const Decomposition& decomp, const FlowSettings& settings);
  ~FlowSolver();

  const FluidGrid& grid() const { return *grid_; }
  // Collective: the grid takes the decomposition's current cut planes (issue 19's rebalancing) and
  // every field is made anew, zero: the caller puts the state back (read_flow_checkpoint, which
  // refreshes ghosts and properties). The clock, timers and settings stay; a cell drag must be set
  // again. References to grid() stay valid (the same object).
  void repartition(const Decomposition& decomp);
  const FlowSettings& settings() const { return settings_; }

  // Initial state: per owned cell, its liquid fraction and its (mass-averaged) velocity. Then the
  // face velocities are projected to be divergence-free (no gravity step).
  struct CellState {
    double liquid_fraction = 0;
    Vec3 velocity;
  };
  void initialize(const std::function<CellState(int i, int j, int k)>& cell);

  // Largest stable dt by the configured limits (collective); `limit` names the active one.
  double stable_dt(std::string& limit) const;
  FlowStepStats advance(double dt);
  // Stage 1 alone: VOF and momentum advection with the current face velocities (kinematic tests
  // set those from outside and call this; the clock does not move).
  void advect(double dt);

  double time() const { return time_; }
  long steps() const { return steps_; }
  double last_dt() const { return last_dt_; }
  // Restart: the clock, and the last step's dt (the growth limit starts from it).
  void set_clock(double time, long steps, double last_dt) {
    time_ = time, steps_ = steps, parity_ = steps, last_dt_ = last_dt;
  }

  // Collective diagnostics over owned cells.
  double liquid_volume() const;
  double kinetic_energy() const;
  double potential_energy() const;  // sum of -rho g . (x - lo) over the cells (J; both phases)
  double max_speed() const;
  double max_face_divergence() const;  // max |div u_f| (1/s)
  // Collective: the volume flux out of the domain through side `side` (0 low, 1 high) of direction
  // d (m^3/s, negative where the flow comes in), from the projected face velocities, summed exactly
  // (the same bits on any rank count). 0 on a wall; not defined on a periodic side (0).
  double boundary_flux(int d, int side) const;
  // Collective: the momentum the domain's walls gave the fluid in the last step (N s), summed
  // exactly: the viscous stress on the wall faces (F8, or the wall law F8a) and the pressure on them,
  // the wall cell's extrapolated half a cell by the hydrostatic gradient its zero face acceleration
  // means (F10). Not counted: outflow sides (their momentum flux), periodic ones (none).
  Vec3 last_wall_impulse() const;
  double min_fraction() const;
  double max_fraction() const;

  // With settings.energy_budget: the kinetic + potential energy (both phases) that each stage has
  // changed since the start or restart (J, summed over steps; theory F12a). The advection moves
  // mass (potential) and momentum (kinetic); the viscous stage and the projection change the
  // kinetic energy, the projection by gravity's work and the pressure's. Their sum is the whole
  // energy's change; without surface tension the exact flow loses only the viscous dissipation and
  // what leaves through open sides.
  struct EnergyBudget {
    double advection = 0, viscous = 0, projection = 0;
  };
  const EnergyBudget& energy_budget() const { return energy_budget_; }
  void set_energy_budget(const EnergyBudget& b) { energy_budget_ = b; }  // a restart's
  // With settings.energy_budget: per owned cell, the kinetic energy its faces' momentum fluxes made
  // in the advection since the start (J/m^3, half of each face's share to each of its two cells; F12a).
  const std::vector<double>& advection_energy_source() const { return advection_source_; }
  std::vector<double>& mutable_advection_energy_source() { return advection_source_; }

  // Fields (ghosted local arrays, see FluidGrid): volume fraction, cell velocity components,
  // pressure, face-normal velocities, density, viscosity.
  const std::vector<double>& fraction() const { return f_; }
  const std::vector<double>& velocity(int d) const { return u_[d]; }
  const std::vector<double>& pressure() const { return p_; }
  const std::vector<double>& face_velocity(int d) const { return uf_[d]; }
  const std::vector<double>& density() const { return rho_; }
  const std::vector<double>& viscosity() const { return mu_; }  // dynamic, Pa s
  // The last projection's face accelerations a_f = g_f - grad_f p / rho_f along d (F10), on the
  // low face of each cell (the coupling's pressure force on bodies reads them).
  const std::vector<double>& face_acceleration(int d) const { return face_accel_[d]; }
  // -grad p in owned cell (i, j, k) (N/m^3), as the last projection applied it: per direction the
  // mean over the cell's two faces of rho_f (a_f - g) (a wall face: -rho g, its normal
  // acceleration being zero). At hydrostatic rest it is -rho g exactly (theory C3).
  Vec3 pressure_force(int i, int j, int k) const;
  std::vector<double>& mutable_fraction() { return f_; }
  std::vector<double>& mutable_velocity(int d) { return u_[d]; }
  std::vector<double>& mutable_pressure() { return p_; }
  std::vector<double>& mutable_face_velocity(int d) { return uf_[d]; }
  // After fields were set from outside (restart): fill ghosts and derived fields.
  void refresh();
  // After owned cell velocities were changed from outside (the coupling's correction): ghosts.
  void velocity_changed();
  // After owned liquid fractions were changed from outside (the coupling's liquid in the fluid
  // part): ghosts, density and viscosity.
  void fraction_changed();
  // On: the viscous stage keeps div(tau) per owned cell (N/m^3; the coupling's viscous force on
  // bodies reads it). Off (the default): not stored.
  void keep_stress_divergence(bool on);
  // On: each step keeps the advection's change of the momentum per volume, (rho u)_after -
  // (rho u)_before, per owned cell (kg/(m^2 s); the coupling's conservative option, theory C8).
  void keep_advection_change(bool on);
  const std::vector<double>& advection_change(int q) const { return advection_change_[q]; }
  // A cell drag held by the caller and applied in each step's projection (nullptr: none).
  void set_cell_drag(const CellDrag* drag) { drag_ = drag; }
  const std::vector<double>& stress_divergence(int q) const { return stress_div_[q]; }

  // Phase timers, with `halo_exchange_fields` and `halo_exchange_multigrid`: the ghost exchanges'
  // share (waiting for the neighbour included), already counted inside the phases that make them.
  PhaseTimers& timers() {
    const double fields = grid_->exchange_seconds(), multigrid = poisson_->exchange_seconds();
    timers_.add("halo_exchange_fields", fields - fields_reported_);
    timers_.add("halo_exchange_multigrid", multigrid - multigrid_reported_);
    fields_reported_ = fields, multigrid_reported_ = multigrid;
    return timers_;
  }
  std::string poisson_description() const { return poisson_->description(); }
  long poisson_coarsest_cells() const { return poisson_->coarsest_cells(); }
  int poisson_levels() const { return poisson_->levels(); }
  int poisson_gathered_levels() const { return poisson_->gathered_levels(); }
  int poisson_two_layer_levels() const { return poisson_->two_layer_levels(); }
  double poisson_exchanges_per_cycle() const { return poisson_->exchanges_per_cycle(); }
  // What this rank's ghost exchanges sent since the start (messages, bytes): the fields' and the
  // multigrid's (PETSc's own traffic in the Krylov solver is not counted).
  CellHalo::Traffic field_traffic() const { return grid_->halo_traffic(); }
  CellHalo::Traffic multigrid_traffic() const {
    CellHalo::Traffic t = multigrid_carried_;
    t += poisson_->halo_traffic();
    return t;
  }

 private:
  void make_fields();        // every grid field, zero
  void update_properties();  // rho, mu from f on the whole ghosted box
  void fill_fraction_ghosts(std::vector<double>& f) const;
  void fill_velocity_ghosts(std::array<std::vector<double>, 3>& u) const;
  void fill_pressure_ghosts();
  void sweep(int d, double dt, bool last);  // one direction of VOF + momentum advection
  // The faces of cells whose new velocity would overshoot take the upwind value (F7).
  void bound_momentum_fluxes(int d, double dt, bool last);
  // A cell's new liquid fraction, density and momentum (per cell volume) from a sweep's face fluxes
  // along the stride st and its dilatation term div (F4, F6, F7).
  struct SweepUpdate {
    double fraction, density, momentum[3];
  };
  SweepUpdate sweep_update(std::size_t c, std::ptrdiff_t st, double div) const;
  double sweep_dilatation(std::size_t c, int d, double dt, bool last) const;  // div of F4's dilatation term
  bool overshoots(std::size_t c, std::ptrdiff_t st, const SweepUpdate& up) const;  // F7's bound
  void store_update(std::size_t c, const SweepUpdate& up);  // into sweep_u_, sweep_f_
  void reconstruct(int d);                  // PLIC in owned cells and one layer beyond along d
  void youngs_normal(std::size_t c, double n[3]) const;
  void interface_potential();               // interface_phi_ (F10b)
  double potential(double a, double b, double c) const;  // g . (x - lo), x in cell widths from lo
  void viscous(double dt);                  // u <- u + dt div(tau) / rho
  void wall_model_stress(double dt);        // the wall law on no-slip walls (after viscous)
  PoissonStats project(double dt, bool with_gravity);
  void wall_pressure_impulse(double dt);    // the walls' pressure impulse of the projection

  FlowSettings settings_;
  std::unique_ptr<FluidGrid> grid_;
  std::unique_ptr<PressurePoisson> poisson_;
  std::vector<double> f_, p_, rho_, mu_, indicator_, dilatation_;
  std::vector<double> upwind_cell_;  // F7's bound: the round in which a cell's faces took the upwind velocity
  std::vector<std::array<int, 3>> bound_marked_, bound_check_, bound_redo_;  // its lists of cells
  std::array<std::vector<double>, 3> sweep_u_;  // a sweep's new velocities and fractions (swapped in)
  std::vector<double> sweep_f_;
  std::array<std::vector<double>, 3> u_, uf_, face_accel_;
  std::array<std::vector<double>, 3> work_;  // the viscous stage's new velocities (swapped into u_)
  std::array<std::vector<double>, 3> stress_div_;  // div(tau) of the last viscous stage, when kept
  std::array<std::vector<double>, 3> advection_change_;  // Delta (rho u) of the last advection, when kept
  std::array<std::vector<double>, 4> plic_;  // nx, ny, nz, alpha of interface cells
  std::vector<double> flux_f_, flux_m_, rhs_;
  const CellDrag* drag_ = nullptr;
  std::vector<double> drag_density_;
  std::vector<double> interface_phi_;  // g . (x - lo) on each interface cell's plane; NaN elsewhere
  double g2_ = 0, h_max_ = 0;
  int down_axis_ = 2;  // gravity's main direction  // rho (1 + lambda dt): the projection's, with a cell drag
  std::array<std::vector<double>, 3> flux_q_;
  EnergyBudget energy_budget_;
  std::vector<double> advection_source_;  // F12a's per-cell source, when the budget is on
  void add_advection_source(int d);  // a sweep's face sources into advection_source_
  std::array<ExactSum, 3> wall_impulse_;  // this rank's wall faces, the current step
  PhaseTimers timers_;
  double time_ = 0;
  long steps_ = 0;
  long parity_ = 0;  // sweeps done: the order alternates
  double last_dt_ = 0;
  double fields_reported_ = 0, multigrid_reported_ = 0;
  CellHalo::Traffic multigrid_carried_;  // the multigrids of earlier partitions
};

}  // namespace tessera
