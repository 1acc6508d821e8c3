// SPDX-License-Identifier: MIT
// The cell multigrid's levels as every rank sees them (docs/theory.md F9a): each level's size, its
// owners' blocks along each direction, the directions gathered from the next finer level, and its
// ghost layers; and the ghost exchanges a V-cycle makes on each. Made from the finest level's cuts
// alone, so that `tessera balance` lays out the levels of P ranks on one process for the scaling
// model; CellMultigrid builds its levels from the same plan.
#pragma once
#include <array>
#include <vector>

namespace tessera {

struct MultigridLevelPlan {
  std::array<int, 3> n{};                  // cells along each direction
  std::array<std::vector<int>, 3> blocks;  // the owners' block lengths along each direction
  // Along each direction, the first cell of the next finer level's aggregate I (I = 0..n, the last
  // entry the finer level's size); empty on the finest level.
  std::array<std::vector<int>, 3> fine_start;
  // Along each direction, each cell's width in finest cells (an odd block's single cell, or a
  // triple, makes a level's widths unequal).
  std::array<std::vector<int>, 3> span;
  // Gathered from the next finer level along d: ranks 2c and 2c + 1 of the finer level hand their
  // aggregates to 2c. parts[d]: the aggregates of each finer block along d (the parts' lengths),
  // before the pairs merge (empty where nothing is gathered).
  std::array<bool, 3> merged{};
  std::array<std::vector<int>, 3> parts;
  // Along d, an aggregate lies across a cut of the next finer level's blocks (level_pairs): it
  // belongs to the rank of its first cell, and its second cell is the next rank's first.
  std::array<bool, 3> crosses{};
  bool crossing() const { return crosses[0] || crosses[1] || crosses[2]; }
  bool halo = false;  // some ghost has a source: a neighbour rank or a periodic image
  int layers = 1;     // ghost layers: 2 lets a red-black sweep follow one exchange
  bool gathered() const { return merged[0] || merged[1] || merged[2]; }
  std::array<int, 3> procs() const { return {int(blocks[0].size()), int(blocks[1].size()), int(blocks[2].size())}; }
  long cells() const { return long(n[0]) * n[1] * n[2]; }
};

// The levels from the finest level's blocks (PETSc's ownership ranges) down to the coarsest.
// ghost_layers: 2 where a level allows it (every split block at least 2 cells across, every face
// at most kTwoLayersFace cells), else 1. level_pairs: the cells paired over the whole level where
// the coarser level is not gathered (one rank's aggregates on any cuts), else within each block.
std::vector<MultigridLevelPlan> plan_multigrid(std::array<std::vector<int>, 3> blocks, const std::array<bool, 3>& periodic,
                                               int ghost_layers, bool level_pairs = false);

// The coarse face coefficient along d on the low side of coarse cell I (I = 0..coarse.n[d]) is the
// sum of the fine coefficients across it over this: the distance between the two coarse centres
// over the distance between the two fine centres across the face, both in finest cells (at a
// domain face, from the centre to the face); 2 between pairs of equal cells (theory F9a).
double coarse_face_distance(const MultigridLevelPlan& fine, const MultigridLevelPlan& coarse, int d, int I,
                            bool periodic);

// Ghost exchanges of one smoothing call (CellMultigrid::smooth): `sweeps` red-black sweeps on a
// level of `layers` ghost layers, from x = 0 or not, the first ghost layer current at the end or not.
int smoothing_exchanges(int sweeps, int layers, bool from_zero, bool ghosts_after);

// Ghost exchanges one V-cycle makes on each level, the operator's one (a Krylov iteration) counted
// on the finest: pre- and post-smoothing on every level but the coarsest, which is solved exactly
// (coarse_direct) or smoothed by coarse_sweeps; where a level's aggregates cross the finer level's
// cuts, one more on each: the finer level's residuals, this level's correction. A level without a
// halo exchanges nothing.
std::vector<int> multigrid_exchanges(const std::vector<MultigridLevelPlan>& plan, int pre, int post, int coarse_sweeps,
                                     bool coarse_direct);

}  // namespace tessera
