// SPDX-License-Identifier: MIT
// Balanced cut planes for the Cartesian process grid (issue 19). The grid keeps its topology
// (dims[d] slabs along each direction, every rank the product of one slab per direction); only the
// interior cut planes move. Along each direction they are put at the weighted quantiles of the
// work's marginal distribution, so that every slab holds the same share of the work; the per-rank
// work of the product grid then follows (exactly balanced when the work separates by direction,
// as a bed filling the bottom of a box does).
//
// Work is a set of samples (a position and a weight: a body and its cost, a cell and its cost).
// Constraints: a slab is at least `min_width` wide (the DEM's contact reach, one flow cell), and
// with a `spacing` > 0 the cuts lie on multiples of it from the box's low side (the flow's cell
// faces: a DMDA owns whole cells).
#pragma once
#include <mpi.h>

#include <array>
#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

struct WorkSample {
  Vec3 x;
  double weight = 1;
};

// Interior cuts (parts - 1 values, increasing, strictly inside (lo, hi)) along one direction.
std::vector<double> balanced_cuts(const std::vector<double>& x, const std::vector<double>& weight, double lo,
                                  double hi, int parts, double min_width = 0, double spacing = 0);

using CutPlanes = std::array<std::vector<double>, 3>;  // interior cuts per direction (Decomposition's)
CutPlanes balanced_cuts(const std::vector<WorkSample>& work, const Vec3& lo, const Vec3& hi, std::array<int, 3> dims,
                        const Vec3& min_width = {}, const Vec3& spacing = {});
CutPlanes equal_cuts(const Vec3& lo, const Vec3& hi, std::array<int, 3> dims);
// Equal slabs of a row of `cells` flow cells over [lo, hi], on cell faces, each slab a whole number
// of 2^k cells for the largest k that leaves the largest slab no larger than equal slabs make it
// (ceil(cells / parts)) and the smallest at least 0.9 of the mean: a multigrid that pairs each
// rank's cells halves such blocks k times without an odd cell (on the paper drop's 176 cells, 5
// slabs: 32, 36, 36, 36, 36 rather than 35, 35, 35, 35, 36; docs/performance.md).
std::vector<double> cell_block_cuts(double lo, double hi, int cells, int parts);
// A flow run's interior cut planes along one direction where the case sets none: cell_block_cuts,
// else equal slabs (scene_flow.cpp; the multigrid's levels laid out as on another grid).
std::vector<double> flow_default_cuts(double lo, double hi, int cells, int parts);

// The grid cell (x fastest) that holds x for interior cuts; outside the box, the boundary slab.
int grid_cell(const Vec3& x, std::array<int, 3> dims, const CutPlanes& interior);
// The work of each rank of the grid (rank order: x fastest) for interior cuts; a sample outside the
// box goes to the boundary slab, as Decomposition::owner_coord does.
std::vector<double> rank_work(const std::vector<WorkSample>& work, std::array<int, 3> dims,
                              const CutPlanes& interior);
// Largest over mean (1 = balanced).
double imbalance(const std::vector<double>& per_rank);

// Work spread evenly over a box (a rank's flow cells: one box, not a sample per cell).
struct WorkBox {
  Vec3 lo, hi;
  double weight = 0;
};

// Collective (every rank its own samples and boxes): the cuts from per-direction histograms of
// `bins` bins over the box, summed over the ranks. With whole-number weights the sums are exact, so
// every rank (and every rank count) gets the same cuts; a cut's resolution is a bin. A box adds its
// weight to the bins it covers in proportion to the length covered.
CutPlanes balanced_cuts(MPI_Comm comm, const std::vector<WorkSample>& local, const Vec3& lo, const Vec3& hi,
                        std::array<int, 3> dims, const Vec3& min_width = {}, const Vec3& spacing = {},
                        int bins = 4096, const std::vector<WorkBox>& boxes = {});
// Collective: the largest rank's work over the mean.
double imbalance(MPI_Comm comm, double local_work);

// Cuts on the spacing (multiples of it from lo, when > 0) with every slab at least min_width,
// moving as few cuts as it takes (balanced_cuts' last step).
void fit_slabs(std::vector<double>& interior, double lo, double hi, double min_width, double spacing);

// Work done in stages that each end in a wait for all ranks (a coupled step: the flow over its
// cells, then the bodies' sub-steps and lay-outs): a step takes, per stage, its busiest rank's
// time. Its imbalance is the sum over the stages of the busiest rank's work over the sum of their
// means (1: every stage balanced).
struct StageWork {
  std::vector<WorkSample> samples;
  std::vector<WorkBox> boxes;
};
double staged_imbalance(const std::vector<std::vector<double>>& per_stage_per_rank);
// Collective: from each rank's work in each stage.
double staged_imbalance(MPI_Comm comm, const std::vector<double>& local_stage_work);
// Collective: each rank's work of one stage (rank order: x fastest) for the interior cuts; a box
// adds its weight to the ranks in proportion to the volume it shares with them.
std::vector<double> rank_work(MPI_Comm comm, const StageWork& stage, const Vec3& lo, const Vec3& hi,
                              std::array<int, 3> dims, const CutPlanes& interior);
// Collective: cut planes for staged work. Equal shares of the stages' summed work do not make a
// staged step fastest when the stages' work lies differently (the flow's cells fill the box evenly,
// the bodies' work thins out at the walls and comes in whole grains): among the cuts now (when
// given; kept on a tie), those that balance the summed work, those that balance each stage alone
// and blends of the two (these on the spacing), equal slabs on the spacing in blocks the multigrid
// halves evenly (cell_block_cuts: a flow run's default) and equal slabs, the cuts whose staged
// imbalance is least.
struct StagedCuts {
  CutPlanes cuts;
  double imbalance = 1;   // staged_imbalance at these cuts
  std::string candidate;  // "current", "summed", "stage K at T" (a blend), "stage K", "cell blocks", "equal"
};
StagedCuts staged_cuts(MPI_Comm comm, const std::vector<StageWork>& stages, const Vec3& lo, const Vec3& hi,
                       std::array<int, 3> dims, const Vec3& min_width = {}, const Vec3& spacing = {}, int bins = 4096,
                       const CutPlanes* current = nullptr);

}  // namespace tessera
