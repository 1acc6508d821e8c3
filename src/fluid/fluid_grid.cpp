// SPDX-License-Identifier: MIT
#include "fluid/fluid_grid.hpp"

#include <algorithm>

#include "core/errors.hpp"
#include "fluid/petsc_check.hpp"

namespace tessera {
namespace {

constexpr auto check = petsc_check;

// Cells per process along d (cells_per_slab on the decomposition's cut planes).
std::vector<PetscInt> ownership(const Decomposition& decomp, int d, int n, double lo, double h) {
  const auto& cuts = decomp.cuts(d);
  const std::vector<int> counts = cells_per_slab(std::vector<double>(cuts.begin() + 1, cuts.end() - 1), n, lo, h);
  return std::vector<PetscInt>(counts.begin(), counts.end());
}

}  // namespace

std::vector<int> cells_per_slab(const std::vector<double>& interior, int n, double lo, double h) {
  std::vector<int> counts(interior.size() + 1, 0);
  for (int i = 0; i < n; ++i) {
    const double x = lo + (i + 0.5) * h;
    counts[std::size_t(std::upper_bound(interior.begin(), interior.end(), x) - interior.begin())]++;
  }
  return counts;
}

const char* boundary_name(BoundaryKind k) {
  switch (k) {
    case BoundaryKind::no_slip:
      return "no_slip";
    case BoundaryKind::free_slip:
      return "free_slip";
    case BoundaryKind::outflow:
      return "outflow";
    case BoundaryKind::periodic:
      return "periodic";
  }
  return "?";
}

FluidGrid::FluidGrid(const Decomposition& decomp, std::array<int, 3> cells,
                     const std::array<std::array<BoundaryKind, 2>, 3>& boundaries)
    : n_(cells), bc_(boundaries) {
  build(decomp);
}

void FluidGrid::repartition(const Decomposition& decomp) {
  release();
  build(decomp);
}

void FluidGrid::build(const Decomposition& decomp) {
  const Vec3 lo = decomp.global_lo(), hi = decomp.global_hi();
  lo_ = lo;
  for (int d = 0; d < 3; ++d) h_[d] = (hi[d] - lo[d]) / n_[d];

  const auto& dims = decomp.dims();
  const auto& coords = decomp.coords();
  const int key = coords[0] + dims[0] * (coords[1] + dims[1] * coords[2]);
  MPI_Comm_split(decomp.comm(), 0, key, &comm_);
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);

  std::array<std::vector<PetscInt>, 3> own;
  for (int d = 0; d < 3; ++d) {
    own[d] = ownership(decomp, d, n_[d], lo[d], h_[d]);
    for (std::size_t r = 0; r < own[d].size(); ++r)
      if (own[d][r] < (dims[d] > 1 || periodic(d) ? kGhost : 1))
        throw InputError("fluid.cells", std::to_string(n_[d]),
                         "at least " + std::to_string(kGhost) + " cells per rank along " + "xyz"[d] + " (" +
                             std::to_string(dims[d]) + " ranks there; process slab " + std::to_string(r) + " gets " +
                             std::to_string(own[d][r]) + ")");
  }
  DMBoundaryType bt[3];
  for (int d = 0; d < 3; ++d) bt[d] = periodic(d) ? DM_BOUNDARY_PERIODIC : DM_BOUNDARY_GHOSTED;
  check(DMDACreate3d(comm_, bt[0], bt[1], bt[2], DMDA_STENCIL_BOX, n_[0], n_[1], n_[2], dims[0], dims[1], dims[2], 1,
                     kGhost, own[0].data(), own[1].data(), own[2].data(), &da_),
        "DMDACreate3d (fields)");
  check(DMSetUp(da_), "DMSetUp");
  check(DMDACreate3d(comm_, bt[0], bt[1], bt[2], DMDA_STENCIL_STAR, n_[0], n_[1], n_[2], dims[0], dims[1], dims[2], 1,
                     1, own[0].data(), own[1].data(), own[2].data(), &dap_),
        "DMDACreate3d (pressure)");
  check(DMSetUp(dap_), "DMSetUp");
  PetscInt xs, ys, zs, xm, ym, zm, gxs, gys, gzs, gxm, gym, gzm;
  check(DMDAGetCorners(da_, &xs, &ys, &zs, &xm, &ym, &zm), "DMDAGetCorners");
  check(DMDAGetGhostCorners(da_, &gxs, &gys, &gzs, &gxm, &gym, &gzm), "DMDAGetGhostCorners");
  s_ = {int(xs), int(ys), int(zs)};
  m_ = {int(xm), int(ym), int(zm)};
  gs_ = {int(gxs), int(gys), int(gzs)};
  gm_ = {int(gxm), int(gym), int(gzm)};
  // The DMDA must hold this rank's sub-box: a mismatch would mean the renumbering is wrong.
  for (int d = 0; d < 3; ++d) {
    PetscInt before = 0;
    for (int r = 0; r < coords[d]; ++r) before += own[d][r];
    if (before != s_[d] || own[d][coords[d]] != m_[d])
      throw RunError("fluid grid: DMDA ownership does not match the DEM decomposition");
  }
  stride_ = {1, gm_[0], std::ptrdiff_t(gm_[0]) * gm_[1]};
  CellHalo::Block block;
  for (int d = 0; d < 3; ++d) block.periodic[d] = periodic(d);
  block.procs = dims;
  block.coords = coords;
  block.s = s_;
  block.m = m_;
  block.gs = gs_;
  block.gm = gm_;
  halo_ = std::make_unique<CellHalo>(comm_, block, kGhost, CellHalo::Stencil::box);
}

FluidGrid::~FluidGrid() { release(); }

void FluidGrid::release() {
  if (halo_) carried_ += halo_->traffic();
  halo_.reset();
  if (dap_) DMDestroy(&dap_);
  if (da_) DMDestroy(&da_);
  if (comm_ != MPI_COMM_NULL) MPI_Comm_free(&comm_);
  dap_ = da_ = nullptr;
  comm_ = MPI_COMM_NULL;
}

void FluidGrid::exchange(std::vector<double>& field) const { exchange({&field}); }

void FluidGrid::exchange(std::initializer_list<std::vector<double>*> fields) const {
  if (!halo_->active()) return;  // one rank, nothing periodic: no ghost has a source
  const double start = MPI_Wtime();
  halo_->exchange(fields);
  exchange_seconds_ += MPI_Wtime() - start;
}

double FluidGrid::sum_owned(const std::vector<double>& values) const {
  double s = 0;
  for (int k = s_[2]; k < s_[2] + m_[2]; ++k)
    for (int j = s_[1]; j < s_[1] + m_[1]; ++j)
      for (int i = s_[0]; i < s_[0] + m_[0]; ++i) s += values[at(i, j, k)];
  return reduce_sum(s);
}

double FluidGrid::reduce_sum(double local) const {
  std::vector<double> all(size_);
  MPI_Allgather(&local, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, comm_);
  double s = 0;
  for (double v : all) s += v;
  return s;
}

double FluidGrid::reduce_max(double local) const {
  MPI_Allreduce(MPI_IN_PLACE, &local, 1, MPI_DOUBLE, MPI_MAX, comm_);
  return local;
}

double FluidGrid::reduce_min(double local) const {
  MPI_Allreduce(MPI_IN_PLACE, &local, 1, MPI_DOUBLE, MPI_MIN, comm_);
  return local;
}

}  // namespace tessera
