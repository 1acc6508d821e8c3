// SPDX-License-Identifier: MIT
// The flow solver's uniform Cartesian grid on a PETSc DMDA (docs/design.md, "One flow step": grid and ranks).
//
// Cells of size dx x dy x dz over the domain box. The DMDA's process grid and ownership ranges are
// the DEM's (src/core/decomposition.hpp): a rank owns the cells whose centres lie in its sub-box,
// so a body and the cells around it live on the same rank. MPI_Cart_create numbers ranks with z
// fastest and a DMDA with x fastest: the DMDA runs on a communicator renumbered so that DMDA rank
// r holds the same sub-box as the Cartesian rank it came from.
//
// Fields are plain arrays over the ghosted local box (two ghost layers, box stencil: PLIC normals
// need the 3x3x3 neighbourhood of a ghost cell). Ghosts between ranks and across periodic
// boundaries are filled by fluid/cell_halo.hpp (in place, no copy of the owned cells); ghosts beyond a
// wall or an outflow are filled by the boundary conditions of flow_solver.
//
// Face-normal velocities live in the same layout: face[d] at cell c is the face on c's low side in
// direction d; the high face of the last owned cell is held by the first ghost cell.
#pragma once
#include <mpi.h>
#include <petscdmda.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "core/decomposition.hpp"
#include "core/vec3.hpp"
#include "fluid/cell_halo.hpp"

namespace tessera {

enum class BoundaryKind { no_slip, free_slip, outflow, periodic };
const char* boundary_name(BoundaryKind k);

// The cells of each slab along one direction of n cells from lo, spacing h: a slab owns the cells
// whose centres lie in it; `interior` the cut planes between the slabs (a rank's ownership range,
// and the multigrid's blocks of another rank count laid out on one process).
std::vector<int> cells_per_slab(const std::vector<double>& interior, int n, double lo, double h);

class FluidGrid {
 public:
  static constexpr int kGhost = 2;

  // boundaries[d][side]: side 0 = low, 1 = high. Periodic must be set on both sides.
  FluidGrid(const Decomposition& decomp, std::array<int, 3> cells,
            const std::array<std::array<BoundaryKind, 2>, 3>& boundaries);
  ~FluidGrid();
  FluidGrid(const FluidGrid&) = delete;
  FluidGrid& operator=(const FluidGrid&) = delete;
  // Collective: the ownership of the decomposition's current cut planes (issue 19's rebalancing;
  // the cuts lie on cell faces). The grid stays the same object; its fields' layout changes, so
  // every field made by make_field must be made again (FlowSolver::repartition).
  void repartition(const Decomposition& decomp);

  MPI_Comm comm() const { return comm_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  DM field_dm() const { return da_; }
  DM pressure_dm() const { return dap_; }  // star stencil, width 1, same ownership (matrix layout)

  const std::array<int, 3>& cells() const { return n_; }
  const Vec3& lo() const { return lo_; }
  double h(int d) const { return h_[d]; }
  double cell_volume() const { return h_[0] * h_[1] * h_[2]; }
  BoundaryKind boundary(int d, int side) const { return bc_[d][side]; }
  bool periodic(int d) const { return bc_[d][0] == BoundaryKind::periodic; }

  // Owned index range [begin, end) and ghosted range [gbegin, gend) per direction (global indices).
  int begin(int d) const { return s_[d]; }
  int end(int d) const { return s_[d] + m_[d]; }
  int gbegin(int d) const { return gs_[d]; }
  int gend(int d) const { return gs_[d] + gm_[d]; }
  std::size_t local_size() const { return std::size_t(gm_[0]) * gm_[1] * gm_[2]; }
  long owned_cells() const { return long(m_[0]) * m_[1] * m_[2]; }
  // Index of global cell (i, j, k) in a local ghosted array, and the stride of direction d.
  std::size_t at(int i, int j, int k) const {
    return (std::size_t(k - gs_[2]) * gm_[1] + std::size_t(j - gs_[1])) * gm_[0] + std::size_t(i - gs_[0]);
  }
  std::ptrdiff_t stride(int d) const { return stride_[d]; }
  // Global indices (i, j, k) of local array index c (the inverse of at()).
  std::array<int, 3> index(std::size_t c) const {
    const int i = int(c % std::size_t(gm_[0])), j = int((c / std::size_t(gm_[0])) % std::size_t(gm_[1]));
    const int k = int(c / (std::size_t(gm_[0]) * std::size_t(gm_[1])));
    return {i + gs_[0], j + gs_[1], k + gs_[2]};
  }
  Vec3 centre(int i, int j, int k) const {
    return {lo_.x + (i + 0.5) * h_[0], lo_.y + (j + 0.5) * h_[1], lo_.z + (k + 0.5) * h_[2]};
  }
  // True when a face-neighbour of an owned cell in direction d, side `side`, lies beyond the domain.
  bool at_domain_edge(int d, int side) const {
    return !periodic(d) && (side == 0 ? s_[d] == 0 : s_[d] + m_[d] == n_[d]);
  }

  // Fills ghosts from neighbour ranks and periodic images (in place, collective).
  void exchange(std::vector<double>& field) const;
  // Same for several fields (one message per neighbour for all of them).
  void exchange(std::initializer_list<std::vector<double>*> fields) const;
  std::vector<double> make_field(double value = 0.0) const { return std::vector<double>(local_size(), value); }

  // Collective sum over owned cells of values[c] (deterministic: each rank sums its cells in index
  // order; the rank sums are combined in rank order on every rank).
  double sum_owned(const std::vector<double>& values) const;
  double reduce_sum(double local) const;  // deterministic, rank-ordered
  double reduce_max(double local) const;
  double reduce_min(double local) const;
  // Wall seconds spent in exchange() so far (communication, inside the phases that call it).
  double exchange_seconds() const { return exchange_seconds_; }
  // Messages and bytes this rank's exchange() calls have sent, over every partition it has had.
  CellHalo::Traffic halo_traffic() const {
    CellHalo::Traffic t = carried_;
    if (halo_) t += halo_->traffic();
    return t;
  }

 private:
  void build(const Decomposition& decomp);
  void release();

  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
  DM da_ = nullptr, dap_ = nullptr;
  std::unique_ptr<CellHalo> halo_;
  mutable double exchange_seconds_ = 0;
  CellHalo::Traffic carried_;  // the earlier partitions' halos'
  std::array<int, 3> n_{}, s_{}, m_{}, gs_{}, gm_{};
  std::array<std::ptrdiff_t, 3> stride_{};
  std::array<double, 3> h_{};
  Vec3 lo_;
  std::array<std::array<BoundaryKind, 2>, 3> bc_{};
};

}  // namespace tessera
