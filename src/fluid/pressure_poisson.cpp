// SPDX-License-Identifier: MIT
#include "fluid/pressure_poisson.hpp"

#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "fluid/petsc_check.hpp"

namespace tessera {
namespace {

constexpr auto check = petsc_check;

}  // namespace

PressurePoisson::PressurePoisson(const FluidGrid& grid, const PoissonSettings& settings)
    : grid_(grid), settings_(settings) {
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side)
      if (grid.boundary(d, side) == BoundaryKind::outflow) singular_ = false;
  DM dm = grid.pressure_dm();
  if (settings_.geometric_multigrid) {
    // Matrix-free: the multigrid's finest level applies the operator from its face coefficients.
    multigrid_ =
        std::make_unique<CellMultigrid>(grid, settings_.pre_sweeps, settings_.post_sweeps, settings_.coarse_sweeps,
                                        settings_.coarse_direct, 2, settings_.levels_as_on, settings_.level_pairs);
    PetscInt local, global;
    Vec probe;
    check(DMCreateGlobalVector(dm, &probe), "DMCreateGlobalVector");
    check(VecGetLocalSize(probe, &local), "VecGetLocalSize");
    check(VecGetSize(probe, &global), "VecGetSize");
    check(VecDestroy(&probe), "VecDestroy");
    check(MatCreateShell(grid.comm(), local, local, global, global, multigrid_.get(), &A_), "MatCreateShell");
    check(MatShellSetOperation(A_, MATOP_MULT,
                               reinterpret_cast<void (*)(void)>(+[](Mat m, Vec x, Vec y) -> PetscErrorCode {
                                 void* ctx;
                                 MatShellGetContext(m, &ctx);
                                 static_cast<CellMultigrid*>(ctx)->apply_operator(x, y);
                                 return 0;
                               })),
          "MatShellSetOperation");
  } else {
    check(DMCreateMatrix(dm, &A_), "DMCreateMatrix");
  }
  check(MatSetOption(A_, MAT_SYMMETRIC, PETSC_TRUE), "MatSetOption");
  check(DMCreateGlobalVector(dm, &x_), "DMCreateGlobalVector");
  check(VecDuplicate(x_, &b_), "VecDuplicate");
  if (singular_) {
    check(MatNullSpaceCreate(grid.comm(), PETSC_TRUE, 0, nullptr, &nullspace_), "MatNullSpaceCreate");
    check(MatSetNullSpace(A_, nullspace_), "MatSetNullSpace");
  }
  if (!settings_.petsc_options.empty())
    check(PetscOptionsInsertString(nullptr, settings_.petsc_options.c_str()), "PetscOptionsInsertString");
  check(KSPCreate(grid.comm(), &ksp_), "KSPCreate");
  check(KSPSetOptionsPrefix(ksp_, "poisson_"), "KSPSetOptionsPrefix");
  check(KSPSetType(ksp_, KSPCG), "KSPSetType");
  check(KSPSetNormType(ksp_, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
  if (settings_.single_reduction) check(KSPCGUseSingleReduction(ksp_, PETSC_TRUE), "KSPCGUseSingleReduction");
  PC pc;
  check(KSPGetPC(ksp_, &pc), "KSPGetPC");
  if (settings_.geometric_multigrid) {
    check(PCSetType(pc, PCSHELL), "PCSetType");
    check(PCShellSetContext(pc, multigrid_.get()), "PCShellSetContext");
    check(PCShellSetApply(pc,
                          [](PC p, Vec x, Vec y) -> PetscErrorCode {
                            void* ctx;
                            PCShellGetContext(p, &ctx);
                            static_cast<CellMultigrid*>(ctx)->apply(x, y);
                            return 0;
                          }),
          "PCShellSetApply");
    check(PCShellSetName(pc, "Tessera cell-centred geometric multigrid"), "PCShellSetName");
  } else {
#if defined(PETSC_HAVE_HYPRE)
    check(PCSetType(pc, PCHYPRE), "PCSetType");
    check(PCHYPRESetType(pc, "boomeramg"), "PCHYPRESetType");
#else
    check(PCSetType(pc, PCGAMG), "PCSetType");
#endif
  }
  check(KSPSetTolerances(ksp_, settings_.rtol, settings_.atol, 1e30, settings_.max_iterations), "KSPSetTolerances");
  check(KSPSetInitialGuessNonzero(ksp_, PETSC_TRUE), "KSPSetInitialGuessNonzero");
  check(KSPSetFromOptions(ksp_), "KSPSetFromOptions");
}

PressurePoisson::~PressurePoisson() {
  if (ksp_) KSPDestroy(&ksp_);
  if (nullspace_) MatNullSpaceDestroy(&nullspace_);
  if (b_) VecDestroy(&b_);
  if (x_) VecDestroy(&x_);
  if (A_) MatDestroy(&A_);
}

std::string PressurePoisson::description() const {
  KSPType kt;
  PCType pt;
  PC pc;
  KSPGetType(ksp_, &kt);
  KSPGetPC(ksp_, &pc);
  PCGetType(pc, &pt);
  std::string s = std::string(kt) + " + " + pt;
  if (std::string(pt) == "hypre") s += " (BoomerAMG)";
  if (std::string(pt) == "shell" && multigrid_)
    s = std::string(kt) + " + geometric multigrid (" + std::to_string(multigrid_->levels()) + " levels, the coarsest " +
        std::to_string(multigrid_->coarsest_cells()) + " cells by " + (settings_.coarse_direct ? "LU" : "sweeps") +
        (settings_.levels_as_on.any() ? ", laid out as on " + std::to_string(settings_.levels_as_on.grid[0]) + "x" +
                                            std::to_string(settings_.levels_as_on.grid[1]) + "x" +
                                            std::to_string(settings_.levels_as_on.grid[2]) + " ranks)"
                                      : ")");
  return s;
}

long PressurePoisson::coarsest_cells() const { return multigrid_ ? multigrid_->coarsest_cells() : 0; }

void PressurePoisson::assemble(const std::vector<double>& rho) {
  const FluidGrid& g = grid_;
  const bool rebuild = settings_.reuse_preconditioner <= 1 || solves_ % settings_.reuse_preconditioner == 0;
  if (multigrid_) {
    // The operator is the multigrid's finest level: its coefficients are always current; a reused
    // preconditioner keeps the coarse levels only.
    multigrid_->set_coefficients(rho, rebuild);
    check(KSPSetOperators(ksp_, A_, A_), "KSPSetOperators");
    return;
  }
  check(MatZeroEntries(A_), "MatZeroEntries");
  const double h[3] = {g.h(0), g.h(1), g.h(2)};
  const double area_over_h[3] = {h[1] * h[2] / h[0], h[0] * h[2] / h[1], h[0] * h[1] / h[2]};
  MatStencil row, cols[7];
  PetscScalar vals[7];
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) {
        const std::size_t c = g.at(i, j, k);
        row = {k, j, i, 0};
        int n = 1;
        double diag = 0;
        const int idx[3] = {i, j, k};
        for (int d = 0; d < 3; ++d)
          for (int side = 0; side < 2; ++side) {
            const int nb = idx[d] + (side ? 1 : -1);
            const bool beyond = nb < 0 || nb >= g.cells()[d];
            if (beyond && !g.periodic(d)) {
              if (g.boundary(d, side) == BoundaryKind::outflow) diag += 2 * area_over_h[d] / rho[c];
              continue;
            }
            const std::size_t cn = c + (side ? 1 : -1) * g.stride(d);
            const double coef = area_over_h[d] / (0.5 * (rho[c] + rho[cn]));
            diag += coef;
            MatStencil s = row;
            if (d == 0) s.i = nb;
            if (d == 1) s.j = nb;
            if (d == 2) s.k = nb;
            cols[n] = s;
            vals[n] = -coef;
            ++n;
          }
        cols[0] = row;
        vals[0] = diag;
        check(MatSetValuesStencil(A_, 1, &row, n, cols, vals, ADD_VALUES), "MatSetValuesStencil");
      }
  check(MatAssemblyBegin(A_, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
  check(MatAssemblyEnd(A_, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
  check(KSPSetReusePreconditioner(ksp_, rebuild ? PETSC_FALSE : PETSC_TRUE), "KSPSetReusePreconditioner");
  check(KSPSetOperators(ksp_, A_, A_), "KSPSetOperators");
}

PoissonStats PressurePoisson::solve(const std::vector<double>& rhs, std::vector<double>& p) {
  const FluidGrid& g = grid_;
  PetscScalar ***bx, ***xx;
  check(DMDAVecGetArray(g.pressure_dm(), b_, &bx), "DMDAVecGetArray");
  check(DMDAVecGetArray(g.pressure_dm(), x_, &xx), "DMDAVecGetArray");
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) {
        bx[k][j][i] = rhs[g.at(i, j, k)];
        xx[k][j][i] = p[g.at(i, j, k)];
      }
  check(DMDAVecRestoreArray(g.pressure_dm(), b_, &bx), "DMDAVecRestoreArray");
  check(DMDAVecRestoreArray(g.pressure_dm(), x_, &xx), "DMDAVecRestoreArray");
  if (nullspace_) check(MatNullSpaceRemove(nullspace_, b_), "MatNullSpaceRemove");

  PoissonStats st;
  check(VecNorm(b_, NORM_2, &st.rhs_norm), "VecNorm");
  ++solves_;
  if (st.rhs_norm == 0) {
    // Nothing drives a flow: p = 0 up to the null space.
    check(VecSet(x_, 0.0), "VecSet");
    st.reason = "zero right-hand side";
  } else {
    check(KSPSolve(ksp_, b_, x_), "KSPSolve");
    KSPConvergedReason reason;
    PetscInt its;
    check(KSPGetConvergedReason(ksp_, &reason), "KSPGetConvergedReason");
    check(KSPGetIterationNumber(ksp_, &its), "KSPGetIterationNumber");
    check(KSPGetResidualNorm(ksp_, &st.residual), "KSPGetResidualNorm");
    st.iterations = int(its);
    st.reason = KSPConvergedReasons[reason];
    if (reason < 0)
      throw CollectiveRunError("pressure Poisson solve did not converge: " + st.reason + " after " +
                               std::to_string(its) + " iterations, residual " + std::to_string(st.residual) +
                               " (|b| = " + std::to_string(st.rhs_norm) + ", rtol " + std::to_string(settings_.rtol) +
                               ")");
  }
  if (nullspace_) check(MatNullSpaceRemove(nullspace_, x_), "MatNullSpaceRemove");
  check(DMDAVecGetArray(g.pressure_dm(), x_, &xx), "DMDAVecGetArray");
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) p[g.at(i, j, k)] = xx[k][j][i];
  check(DMDAVecRestoreArray(g.pressure_dm(), x_, &xx), "DMDAVecRestoreArray");
  return st;
}

}  // namespace tessera
