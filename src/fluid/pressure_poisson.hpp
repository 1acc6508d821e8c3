// SPDX-License-Identifier: MIT
// The variable-coefficient pressure Poisson equation of the projection (docs/theory.md F9):
//
//   sum over faces of A_f / (h_f rho_f) (p_c - p_nb) = -(1/dt) sum over faces of A_f u*_f . n_f
//
// on 7 points, rho_f the face density (mean of the two cells). Walls carry no flux (no term);
// an outflow face holds p = 0 at the face (p_ghost = -p_c, coefficient doubled); periodic faces
// couple across the domain. Without an outflow face the operator is singular: the constants are
// declared as its null space and removed from the right-hand side.
//
// Solved with PETSc KSP on the pressure DMDA: CG (unpreconditioned residual norm, so that the
// tolerance means the same for every preconditioner) preconditioned by Tessera's cell-centred
// geometric multigrid (cell_multigrid.hpp, `preconditioner: multigrid`, the default) or by any
// PETSc preconditioner (`preconditioner: petsc`: hypre BoomerAMG unless -poisson_pc_type says
// otherwise); the previous pressure is the initial guess. Options prefix `poisson_`: anything in the case's
// fluid.poisson.petsc_options or on the command line (-poisson_pc_type gamg ...) overrides.
// A solve that does not converge throws, never returns a silent step.
#pragma once
#include <petscksp.h>

#include <string>
#include <vector>

#include "fluid/cell_multigrid.hpp"
#include "fluid/fluid_grid.hpp"

namespace tessera {

struct PoissonSettings {
  double rtol = 1e-8;  // relative to |b|
  double atol = 0;     // absolute residual (units of the equation: m^3/s)
  int max_iterations = 500;
  std::string petsc_options;        // inserted before KSPSetFromOptions, e.g. "-poisson_pc_type gamg"
  int reuse_preconditioner = 1;     // rebuild the preconditioner every N solves (1 = every solve)
  bool geometric_multigrid = true;  // false: a PETSc preconditioner (options decide which)
  int pre_sweeps = 2, post_sweeps = 2, coarse_sweeps = 20;  // the V-cycle's smoothing
  bool coarse_direct = true;  // the coarsest level solved by LU (else coarse_sweeps; theory F9a)
  // `multigrid.levels_as_on` (issue 19): on one process, the levels another process grid would make
  // (cell_multigrid.hpp), so that one process counts that rank count's iterations.
  LevelsAsOn levels_as_on;
  // `multigrid.pairs`: "level" (default) or "blocks" (each rank's block paired on its own). "level": the whole level
  // paired, pairs across a cut included, where it is not gathered: one rank's aggregates, and so its
  // V-cycle's numbers, on any cuts; cell_multigrid.hpp, theory F9a).
  bool level_pairs = true;
  // CG's two inner products an iteration merged into one reduction (Chronopoulos & Gear; PETSc's
  // KSPCGUseSingleReduction): 2 reductions an iteration with the residual's norm, instead of 3.
  // Off by default: 5 % slower on 2 ranks, and the reductions are not where many ranks wait (F9).
  bool single_reduction = false;
};

struct PoissonStats {
  int iterations = 0;
  double residual = 0;  // unpreconditioned 2-norm at the end
  double rhs_norm = 0;
  std::string reason;
};

class PressurePoisson {
 public:
  PressurePoisson(const FluidGrid& grid, const PoissonSettings& settings);
  ~PressurePoisson();
  PressurePoisson(const PressurePoisson&) = delete;
  PressurePoisson& operator=(const PressurePoisson&) = delete;

  // rho: ghosted cell densities (ghosts valid). Builds the matrix.
  void assemble(const std::vector<double>& rho);
  // rhs: ghosted array, values on owned cells. p: ghosted, owned values are the initial guess and
  // receive the solution. Throws CollectiveRunError when KSP does not converge.
  PoissonStats solve(const std::vector<double>& rhs, std::vector<double>& p);
  bool singular() const { return singular_; }
  std::string description() const;  // KSP and PC types, for the log
  long coarsest_cells() const;       // the multigrid's coarsest level (0 without it)
  int levels() const { return multigrid_ ? multigrid_->levels() : 0; }
  int gathered_levels() const { return multigrid_ ? multigrid_->gathered_levels() : 0; }
  int two_layer_levels() const { return multigrid_ ? multigrid_->two_layer_levels() : 0; }
  double exchanges_per_cycle() const { return multigrid_ ? multigrid_->exchanges_per_cycle() : 0.0; }
  double exchange_seconds() const { return multigrid_ ? multigrid_->exchange_seconds() : 0.0; }
  CellHalo::Traffic halo_traffic() const { return multigrid_ ? multigrid_->halo_traffic() : CellHalo::Traffic{}; }

 private:
  const FluidGrid& grid_;
  PoissonSettings settings_;
  Mat A_ = nullptr;
  Vec x_ = nullptr, b_ = nullptr;
  KSP ksp_ = nullptr;
  MatNullSpace nullspace_ = nullptr;
  std::unique_ptr<CellMultigrid> multigrid_;
  bool singular_ = true;
  long solves_ = 0;
};

}  // namespace tessera
