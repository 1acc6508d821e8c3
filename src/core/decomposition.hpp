// SPDX-License-Identifier: MIT
// 3D Cartesian process grid over an axis-aligned box (MPI_Cart_create). The fluid's DMDA uses the
// same ranks and ownership ranges. Ownership is by position: the rank whose sub-box holds a body's
// centre owns it; points outside the global box belong to the boundary rank (clamped), so bodies
// that overshoot a wall are never lost.
#pragma once
#include <mpi.h>

#include <array>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

class Decomposition {
 public:
  // requested[d] == 0 lets the grid choose that direction (least sub-domain surface). Interior cut
  // planes per direction (`interior[d]`: dims[d] - 1 increasing values strictly inside the box; empty:
  // equal slabs) move the sub-domains' faces without changing the grid's topology: a rank's share
  // of the work follows where its faces are, and results do not depend on them.
  using Cuts = std::array<std::vector<double>, 3>;
  Decomposition(MPI_Comm comm, const Vec3& lo, const Vec3& hi, std::array<int, 3> requested = {0, 0, 0},
                const Cuts& interior = {});
  ~Decomposition();
  Decomposition(const Decomposition&) = delete;
  Decomposition& operator=(const Decomposition&) = delete;

  MPI_Comm comm() const { return cart_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  const std::array<int, 3>& dims() const { return dims_; }
  const std::array<int, 3>& coords() const { return coords_; }
  const Vec3& global_lo() const { return global_lo_; }
  const Vec3& global_hi() const { return global_hi_; }
  Vec3 sub_lo() const;
  Vec3 sub_hi() const;
  // Neighbour rank across the low (dir = 0) or high (dir = 1) face in direction d, or MPI_PROC_NULL.
  int neighbor(int d, int dir) const { return neighbors_[d][dir]; }
  // Grid coordinate along d that owns coordinate x (clamped to the grid).
  int owner_coord(int d, double x) const;
  bool owns(const Vec3& p) const;
  int owner_rank(const Vec3& p) const;
  // Cut planes along d: dims[d] + 1 values from global_lo[d] to global_hi[d].
  const std::vector<double>& cuts(int d) const { return cuts_[d]; }
  // The interior cut planes (dims[d] - 1 per direction), and moving them (every rank alike, the
  // same values; the grid's topology, ranks and neighbours stay). Whoever holds data by position
  // moves it after (DemSolver::rebalance).
  Cuts interior_cuts() const;
  void set_cuts(const Cuts& interior);

  static std::array<int, 3> choose_dims(int size, const Vec3& extent, std::array<int, 3> requested);

 private:
  MPI_Comm cart_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
  std::array<int, 3> dims_{1, 1, 1}, coords_{0, 0, 0};
  std::array<std::array<int, 2>, 3> neighbors_{};
  Vec3 global_lo_, global_hi_;
  std::array<std::vector<double>, 3> cuts_;
};

}  // namespace tessera
