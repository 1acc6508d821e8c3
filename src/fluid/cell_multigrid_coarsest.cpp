// SPDX-License-Identifier: MIT
// The multigrid's coarsest level solved exactly (cell_multigrid.hpp; docs/theory.md F9a): its
// operator gathered to every rank in the level's natural order and factored by LU there, and each
// cycle's right-hand side gathered the same way, so the same arithmetic on any rank count.
#include <algorithm>

#include "fluid/cell_multigrid.hpp"
#include "fluid/cell_multigrid_detail.hpp"
#include "fluid/petsc_check.hpp"

namespace tessera {
namespace {

constexpr auto check = petsc_check;
using multigrid_detail::coefficient_sum;
using multigrid_detail::for_owned;

}  // namespace

template <class F>
void CellMultigrid::for_natural(F&& fn) const {
  const auto& n = levels_.back()->n;
  std::size_t at = 0;
  for (std::size_t r = 0; 6 * r < coarse_blocks_.size(); ++r) {
    const int* b = &coarse_blocks_[6 * r];  // s[3], m[3]
    for (int k = b[2]; k < b[2] + b[5]; ++k)
      for (int j = b[1]; j < b[1] + b[4]; ++j)
        for (int i = b[0]; i < b[0] + b[3]; ++i, ++at) fn((std::size_t(k) * n[1] + j) * n[0] + i, at);
  }
}

void CellMultigrid::assemble_coarsest() {
  Level& L = *levels_.back();
  const MPI_Comm comm = L.comm;
  int size = 1;
  MPI_Comm_size(comm, &size);
  const long cells = coarsest_cells();
  if (!coarse_A_) {
    const int mine[6] = {L.s[0], L.s[1], L.s[2], L.m[0], L.m[1], L.m[2]};
    coarse_blocks_.resize(6 * std::size_t(size));
    MPI_Allgather(mine, 6, MPI_INT, coarse_blocks_.data(), 6, MPI_INT, comm);
    coarse_counts_.resize(std::size_t(size));
    coarse_displs_.resize(std::size_t(size));
    for (int r = 0, at = 0; r < size; ++r) {
      const int* b = &coarse_blocks_[6 * std::size_t(r)];
      coarse_counts_[std::size_t(r)] = b[3] * b[4] * b[5];
      coarse_displs_[std::size_t(r)] = at;
      at += coarse_counts_[std::size_t(r)];
    }
    check(MatCreateSeqAIJ(PETSC_COMM_SELF, PetscInt(cells), PetscInt(cells), 7, nullptr, &coarse_A_), "MatCreateSeqAIJ");
    check(VecCreateSeq(PETSC_COMM_SELF, PetscInt(cells), &coarse_b_), "VecCreateSeq");
    check(VecDuplicate(coarse_b_, &coarse_x_), "VecDuplicate");
    check(KSPCreate(PETSC_COMM_SELF, &coarse_ksp_), "KSPCreate (coarsest level)");
    check(KSPSetOptionsPrefix(coarse_ksp_, "tessera_coarse_"), "KSPSetOptionsPrefix");
    check(KSPSetType(coarse_ksp_, KSPPREONLY), "KSPSetType");
    PC pc;
    check(KSPGetPC(coarse_ksp_, &pc), "KSPGetPC");
    check(PCSetType(pc, PCLU), "PCSetType (lu)");
  }
  // Per owned cell, in its block's order: the diagonal (the smoother's, 1 for a zero row) and the
  // six face coefficients (low x, high x, low y, ...), gathered to every rank.
  constexpr int kPer = 7;
  coarse_mine_.clear();
  for_owned(L.s, L.m, [&](int i, int j, int k) {
    const std::size_t c = L.at(i, j, k);
    coarse_mine_.push_back(coefficient_sum(L, c) > 0 ? 1 / double(L.inv_diag[c]) : 1.0);
    for (int d = 0; d < 3; ++d)
      coarse_mine_.push_back(double(L.coef[d][c])), coarse_mine_.push_back(double(L.coef[d][c + L.stride[d]]));
  });
  std::vector<int> counts(coarse_counts_), displs(coarse_displs_);
  for (auto& v : counts) v *= kPer;
  for (auto& v : displs) v *= kPer;
  coarse_all_.resize(std::size_t(kPer) * std::size_t(cells));
  MPI_Allgatherv(coarse_mine_.data(), int(coarse_mine_.size()), MPI_DOUBLE, coarse_all_.data(), counts.data(),
                 displs.data(), MPI_DOUBLE, comm);
  std::vector<double> row(std::size_t(kPer) * std::size_t(cells));
  for_natural([&](std::size_t natural, std::size_t at) {
    std::copy_n(&coarse_all_[kPer * at], kPer, &row[kPer * natural]);
  });
  // Without any outflow face the operator is singular (constants): the first cell's diagonal is
  // doubled, which keeps the solve symmetric positive definite.
  const auto& n = L.n;
  double outflow = 0;
  for (long c = 0; c < cells; ++c) {
    const int idx[3] = {int(c % n[0]), int((c / n[0]) % n[1]), int(c / (long(n[0]) * n[1]))};
    for (int d = 0; d < 3; ++d)
      if (!grid_.periodic(d)) {
        if (idx[d] == 0) outflow += row[kPer * std::size_t(c) + 1 + 2 * d];
        if (idx[d] == n[d] - 1) outflow += row[kPer * std::size_t(c) + 2 + 2 * d];
      }
  }
  check(MatZeroEntries(coarse_A_), "MatZeroEntries");
  const PetscInt stride[3] = {1, n[0], PetscInt(n[0]) * n[1]};
  for (long c = 0; c < cells; ++c) {
    const double* r = &row[kPer * std::size_t(c)];
    const int idx[3] = {int(c % n[0]), int((c / n[0]) % n[1]), int(c / (long(n[0]) * n[1]))};
    PetscInt cols[7];
    PetscScalar v[7];
    int m = 0;
    cols[m] = PetscInt(c), v[m++] = c == 0 && outflow == 0 ? 2 * r[0] : r[0];
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side) {
        const double cf = r[1 + 2 * d + side];
        int nb = idx[d] + (side ? 1 : -1);
        if (nb < 0 || nb >= n[d]) {
          if (!grid_.periodic(d)) continue;  // a domain face: its term is on the diagonal only
          nb = (nb + n[d]) % n[d];
        }
        if (cf == 0) continue;
        cols[m] = PetscInt(c) + (nb - idx[d]) * stride[d], v[m++] = -cf;
      }
    // Added (after the zeroing): two faces towards one neighbour (a periodic length of 2) sum.
    const PetscInt rc = PetscInt(c);
    check(MatSetValues(coarse_A_, 1, &rc, m, cols, v, ADD_VALUES), "MatSetValues");
  }
  check(MatAssemblyBegin(coarse_A_, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
  check(MatAssemblyEnd(coarse_A_, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
  check(KSPSetOperators(coarse_ksp_, coarse_A_, coarse_A_), "KSPSetOperators (coarsest level)");
  check(KSPSetUp(coarse_ksp_), "KSPSetUp (coarsest level)");
}

void CellMultigrid::solve_coarsest() {
  Level& L = *levels_.back();
  coarse_mine_.clear();
  for_owned(L.s, L.m, [&](int i, int j, int k) { coarse_mine_.push_back(L.b[L.at(i, j, k)]); });
  coarse_all_.resize(std::size_t(coarsest_cells()));
  MPI_Allgatherv(coarse_mine_.data(), int(coarse_mine_.size()), MPI_DOUBLE, coarse_all_.data(), coarse_counts_.data(),
                 coarse_displs_.data(), MPI_DOUBLE, L.comm);
  PetscScalar* b;
  check(VecGetArray(coarse_b_, &b), "VecGetArray");
  for_natural([&](std::size_t natural, std::size_t at) { b[natural] = coarse_all_[at]; });
  check(VecRestoreArray(coarse_b_, &b), "VecRestoreArray");
  check(KSPSolve(coarse_ksp_, coarse_b_, coarse_x_), "KSPSolve (coarsest level)");
  const PetscScalar* x;
  check(VecGetArrayRead(coarse_x_, &x), "VecGetArrayRead");
  const auto& n = L.n;
  for_owned(L.s, L.m, [&](int i, int j, int k) { L.x[L.at(i, j, k)] = x[(std::size_t(k) * n[1] + j) * n[0] + i]; });
  check(VecRestoreArrayRead(coarse_x_, &x), "VecRestoreArrayRead");
}

}  // namespace tessera
