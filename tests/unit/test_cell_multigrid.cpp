// SPDX-License-Identifier: MIT
// The pressure's geometric multigrid (cell_multigrid.hpp) on grids whose sizes are odd, so that
// coarse cells of one fine cell occur (at the end of every odd block), on 1, 2 and 4 ranks:
// - the V-cycle is a symmetric positive definite operator (CG needs it; a restriction that is not
//   the prolongation's transpose breaks the symmetry at round-off's 1e-16 times ~1e6);
// - odd sizes coarsen: 45 x 45 x 33 cells get at least 4 levels (before: 1; no direction could be
//   halved);
// - the preconditioned CG reaches 1e-10 on a 1000:1 density field (a heavy drop and a pool, the
//   flow's own case) in no more iterations than the even grid 44 x 44 x 32 plus 2 (measured
//   2026-12-01: 10 and 10 on 1, 2 and 4 ranks; ending odd blocks in a triple instead: 13-14.
//   2026-12-06, coarse distances in finest cells and a narrower last cell joining its pair: 11 and 10.
//   Before odd sizes coarsened: 36 against 12), and the solution
//   satisfies the 7-point equations (residual computed here from the densities, not by the solver)
//   to that tolerance.
#include <gtest/gtest.h>
#include <mpi.h>
#include <petscdmda.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "core/decomposition.hpp"
#include "core/errors.hpp"
#include "fluid/cell_multigrid.hpp"
#include "fluid/fluid_grid.hpp"
#include "fluid/multigrid_plan.hpp"
#include "fluid/pressure_poisson.hpp"

using namespace tessera;

namespace {

constexpr double kL = 1.0;  // box (0, 1) x (0, 1) x (0, 0.75)

struct Problem {
  Decomposition decomp;
  FluidGrid grid;
  std::vector<double> rho;
  explicit Problem(std::array<int, 3> n, MPI_Comm comm = MPI_COMM_WORLD, BoundaryKind x_sides = BoundaryKind::no_slip,
                   std::array<int, 3> procs = {0, 0, 0})
      : decomp(comm, {0, 0, 0}, {kL, kL, 0.75 * kL}, procs),
        grid(decomp, n,
             {{{x_sides, x_sides},
               {BoundaryKind::free_slip, BoundaryKind::free_slip},
               {BoundaryKind::no_slip, BoundaryKind::outflow}}}) {
    rho.assign(grid.local_size(), 1.0);
    for (int k = grid.gbegin(2); k < grid.gend(2); ++k)
      for (int j = grid.gbegin(1); j < grid.gend(1); ++j)
        for (int i = grid.gbegin(0); i < grid.gend(0); ++i) {
          const Vec3 x = grid.centre(i, j, k);
          const double dx = x.x - 0.45, dy = x.y - 0.55, dz = x.z - 0.5;
          const bool drop = dx * dx + dy * dy + dz * dz < 0.15 * 0.15;
          rho[grid.at(i, j, k)] = drop || x.z < 0.25 ? 1000.0 : 1.0;
        }
  }
  // A smooth right-hand side with every scale in it, from global indices (rank independent).
  double source(int i, int j, int k) const {
    return std::sin(0.37 * i + 1.3 * j) * std::cos(0.71 * k + 0.2 * i) + 0.3 * std::sin(2.9 * (i + j + k));
  }
};

double dot(Vec a, Vec b) {
  PetscScalar d;
  VecDot(a, b, &d);
  return double(d);
}

TEST(CellMultigrid, OddSizesCoarsenAndTheVCycleIsSymmetricPositive) {
  Problem P({45, 45, 33});
  CellMultigrid mg(P.grid);
  mg.set_coefficients(P.rho);
  EXPECT_GE(mg.levels(), 4);
  Vec x, y, mx, my;
  DMCreateGlobalVector(P.grid.pressure_dm(), &x);
  VecDuplicate(x, &y);
  VecDuplicate(x, &mx);
  VecDuplicate(x, &my);
  PetscScalar *px, *py;
  VecGetArray(x, &px);
  VecGetArray(y, &py);
  std::size_t n = 0;
  const FluidGrid& g = P.grid;
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i, ++n) {
        px[n] = P.source(i, j, k);
        py[n] = std::cos(0.53 * i * j + 0.11 * k) + 0.5;
      }
  VecRestoreArray(x, &px);
  VecRestoreArray(y, &py);
  mg.apply(x, mx);
  mg.apply(y, my);
  const double xmy = dot(x, my), mxy = dot(mx, y);
  const double scale = std::sqrt(dot(x, mx) * dot(y, my));
  EXPECT_GT(dot(x, mx), 0.0);
  EXPECT_GT(dot(y, my), 0.0);
  EXPECT_LT(std::abs(xmy - mxy), 1e-12 * scale) << xmy << " against " << mxy;
  for (Vec* v : {&x, &y, &mx, &my}) VecDestroy(v);
}

// One V-cycle applied to the source, on `comm`, as a whole-grid array (x fastest) on every rank of
// it: each rank writes its own cells, the rest are 0, summed (adding zeros is exact).
std::vector<double> vcycle_of_source(std::array<int, 3> n, MPI_Comm comm, BoundaryKind x_sides,
                                     std::array<int, 3> procs = {0, 0, 0}, int* levels = nullptr,
                                     int* gathered = nullptr, int ghost_layers = 2, long* messages = nullptr,
                                     const LevelsAsOn& as_on = {}, bool level_pairs = false) {
  Problem P(n, comm, x_sides, procs);
  const FluidGrid& g = P.grid;
  CellMultigrid mg(g, 2, 2, 20, true, ghost_layers, as_on, level_pairs);
  if (levels) *levels = mg.levels();
  if (gathered) *gathered = mg.gathered_levels();
  mg.set_coefficients(P.rho);
  Vec x, y;
  DMCreateGlobalVector(g.pressure_dm(), &x);
  VecDuplicate(x, &y);
  PetscScalar* px;
  VecGetArray(x, &px);
  std::size_t m = 0;
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) px[m++] = P.source(i, j, k);
  VecRestoreArray(x, &px);
  const long sent = mg.halo_traffic().messages;
  mg.apply(x, y);
  if (messages) *messages = mg.halo_traffic().messages - sent;
  const std::size_t cells = std::size_t(n[0]) * n[1] * n[2];
  std::vector<double> mine(cells, 0.0), all(cells);
  const PetscScalar* py;
  VecGetArrayRead(y, &py);
  m = 0;
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) mine[(std::size_t(k) * n[1] + j) * n[0] + i] = py[m++];
  VecRestoreArrayRead(y, &py);
  MPI_Allreduce(mine.data(), all.data(), int(all.size()), MPI_DOUBLE, MPI_SUM, comm);
  VecDestroy(&x);
  VecDestroy(&y);
  return all;
}

// Where every rank's block pairs up into the same aggregates as one rank's grid on every level
// (32^3: 32 -> 16 -> 8 -> 4 on any of these splits), the V-cycle is the same arithmetic on any rank
// count: the smoother's passes over the cells beside a neighbour's ghosts wait for the exchange
// (the interior's second colour trails the first by a plane), and a cell missed or updated
// before its neighbours' new values arrived would change the bits. With walls and with x
// periodic (ghosts a rank fills from itself).
TEST(CellMultigrid, TheVCycleGivesTheSameBitsOnAnyRankCount) {
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  for (const BoundaryKind x_sides : {BoundaryKind::no_slip, BoundaryKind::periodic}) {
    const std::array<int, 3> n{32, 32, 32};
    const std::vector<double> ranks = vcycle_of_source(n, MPI_COMM_WORLD, x_sides);
    if (rank != 0) continue;
    const std::vector<double> one = vcycle_of_source(n, MPI_COMM_SELF, x_sides);
    std::size_t differ = 0, first = 0;
    for (std::size_t c = 0; c < one.size(); ++c)
      if (ranks[c] != one[c] && differ++ == 0) first = c;
    EXPECT_EQ(differ, 0u) << size << " ranks against 1, x " << boundary_name(x_sides) << ": first at cell " << first
                          << ", " << ranks[first] << " against " << one[first];
    EXPECT_NE(one[n[0] / 2], 0.0);
  }
}

// With two ghost layers the smoother updates the first ghost layer too and exchanges once a sweep
// instead of once a pass (theory F9a): the same arithmetic, so the same bits as with one layer, in
// fewer messages. Odd sizes on 1, 2 and 4 ranks (the coarse blocks of 1 cell keep one layer on
// their levels), walls with an outflow face, and x periodic (a rank's own images).
TEST(CellMultigrid, TwoGhostLayersGiveOneLayersBitsInFewerMessages) {
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  struct Case {
    std::array<int, 3> n;
    BoundaryKind x_sides;
  };
  for (const Case& cs : {Case{{45, 45, 33}, BoundaryKind::no_slip}, Case{{32, 30, 30}, BoundaryKind::periodic}}) {
    long one_layer = 0, two_layers = 0;
    const std::vector<double> a = vcycle_of_source(cs.n, MPI_COMM_WORLD, cs.x_sides, {0, 0, 0}, nullptr, nullptr, 1, &one_layer);
    const std::vector<double> b = vcycle_of_source(cs.n, MPI_COMM_WORLD, cs.x_sides, {0, 0, 0}, nullptr, nullptr, 2, &two_layers);
    std::size_t differ = 0, first = 0;
    for (std::size_t c = 0; c < a.size(); ++c)
      if (a[c] != b[c] && differ++ == 0) first = c;
    EXPECT_EQ(differ, 0u) << size << " ranks, x " << boundary_name(cs.x_sides) << ": first at cell " << first << ", "
                          << b[first] << " with two layers against " << a[first];
    EXPECT_NE(a[cs.n[0] / 2], 0.0);
    if (size > 1) {
      EXPECT_LT(double(two_layers), 0.8 * double(one_layer)) << "rank " << rank;
    }
  }
}

// Where the ranks' blocks would fall below 2 cells, the coarser level is gathered onto half the
// ranks along that direction (theory F9a), so the levels go on as one rank's: 16 x 48 x 48 cells
// on 4 x 1 x 1 ranks (blocks of 4) take 16 -> 8 (blocks of 2) -> 4 (on 2 ranks) -> 2 (on 1) along
// x (one gather on 2 ranks), 4 levels as on one rank, and with blocks that pair up as one rank's the same bits (before,
// x stopped at 8 cells while y and z went on: 5 levels, other numbers). With walls and with x
// periodic; and on 2 x 2 x 1 ranks, 8 x 8 x 96 cells gathered along x and y at once (three parts
// to one owner): 8 -> 4 (blocks of 2) -> 2 (on 1 rank), one rank's 3 levels.
TEST(CellMultigrid, SmallBlocksAreGatheredOntoFewerRanksAndKeepOneRanksLevels) {
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  struct Split {
    std::array<int, 3> n, procs;
    int levels, gathered;  // one rank's levels; the levels gathered on `procs`
  };
  std::vector<Split> splits{{{16, 48, 48}, {size, 1, 1}, 4, size == 4 ? 2 : size == 2 ? 1 : 0}};
  if (size == 4) splits.push_back({{8, 8, 96}, {2, 2, 1}, 3, 1});
  for (const Split& split : splits)
  for (const BoundaryKind x_sides : {BoundaryKind::no_slip, BoundaryKind::periodic}) {
    const std::array<int, 3> n = split.n;
    int levels = 0, one_levels = 0, gathered = 0;
    const std::vector<double> ranks = vcycle_of_source(n, MPI_COMM_WORLD, x_sides, split.procs, &levels, &gathered);
    EXPECT_EQ(gathered, split.gathered);
    if (rank != 0) continue;
    const std::vector<double> one = vcycle_of_source(n, MPI_COMM_SELF, x_sides, {1, 1, 1}, &one_levels);
    EXPECT_EQ(levels, one_levels) << size << " ranks, " << n[0] << " x " << n[1] << " x " << n[2];
    EXPECT_EQ(one_levels, split.levels);
    std::size_t differ = 0, first = 0;
    for (std::size_t c = 0; c < one.size(); ++c)
      if (ranks[c] != one[c] && differ++ == 0) first = c;
    EXPECT_EQ(differ, 0u) << size << " ranks against 1, x " << boundary_name(x_sides) << ": first at cell " << first
                          << ", " << ranks[first] << " against " << one[first];
  }
}

// Solves A p = b (b: Problem's source) with the multigrid-preconditioned CG to `st`.
PoissonStats solve_source(const Problem& P, const PoissonSettings& st, std::vector<double>& b, std::vector<double>& p) {
  const FluidGrid& g = P.grid;
  PressurePoisson poisson(g, st);
  poisson.assemble(P.rho);
  b.assign(g.local_size(), 0.0);
  p.assign(g.local_size(), 0.0);
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) b[g.at(i, j, k)] = P.source(i, j, k);
  return poisson.solve(b, p);
}

// CG's iterations to 1e-10 on `comm` (the heavy drop and pool of Problem).
int iterations_on(std::array<int, 3> n, MPI_Comm comm, BoundaryKind x_sides, std::array<int, 3> procs,
                  const LevelsAsOn& as_on = {}, bool level_pairs = false) {
  const Problem P(n, comm, x_sides, procs);
  PoissonSettings st;
  st.rtol = 1e-10;
  st.levels_as_on = as_on;
  st.level_pairs = level_pairs;
  std::vector<double> b, p;
  return solve_source(P, st, b, p).iterations;
}

// The levels of P ranks laid out on one process (`fluid.poisson.multigrid.levels_as_on`, issue 19:
// the scaling model counts the iterations of rank counts that do not fit here): the V-cycle is P
// ranks' to the bit and CG takes P ranks' iterations, where one process's own levels differ (odd
// blocks end in single cells or triples, small blocks are gathered). The ranks of this test along
// x, then along y (equal slabs, as the test's decomposition cuts them), walls and x periodic. Also refused: on more than one process, and cuts that do not match the grid.
TEST(CellMultigrid, LevelsLaidOutAsOnAnotherGridTakeItsIterations) {
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size > 1) {
    LevelsAsOn on_two;
    on_two.grid = {2, 1, 1};
    EXPECT_THROW(iterations_on({45, 45, 33}, MPI_COMM_WORLD, BoundaryKind::no_slip, {0, 0, 0}, on_two), InputError);
  }
  if (rank == 0) {
    LevelsAsOn bad;
    bad.grid = {3, 1, 1};
    bad.cuts[0] = {0.5};  // 2 planes needed
    EXPECT_THROW(iterations_on({45, 45, 33}, MPI_COMM_SELF, BoundaryKind::no_slip, {1, 1, 1}, bad), InputError);
    bad.cuts[0] = {0.6, 0.3};  // not increasing
    EXPECT_THROW(iterations_on({45, 45, 33}, MPI_COMM_SELF, BoundaryKind::no_slip, {1, 1, 1}, bad), InputError);
  }
  if (size == 1) return;  // P ranks are this test's own
  struct Split {
    std::array<int, 3> n, procs;
  };
  for (const Split& split : {Split{{45, 45, 33}, {size, 1, 1}}, Split{{24, 46, 40}, {1, size, 1}}})
    for (const BoundaryKind x_sides : {BoundaryKind::no_slip, BoundaryKind::periodic}) {
      if (x_sides == BoundaryKind::periodic && split.n[0] % 2) continue;  // red-black needs an even periodic size
      LevelsAsOn as_on;  // the cut planes of Problem's decomposition: equal slabs of the box
      as_on.grid = split.procs;
      const double box[3] = {kL, kL, 0.75 * kL};
      for (int d = 0; d < 3; ++d)
        for (int c = 1; c < split.procs[d]; ++c) as_on.cuts[d].push_back(box[d] * c / split.procs[d]);
      int levels = 0, gathered = 0, as_levels = 0;
      const std::vector<double> ranks = vcycle_of_source(split.n, MPI_COMM_WORLD, x_sides, split.procs, &levels, &gathered);
      const int ranks_iterations = iterations_on(split.n, MPI_COMM_WORLD, x_sides, split.procs);
      if (rank != 0) continue;
      const std::vector<double> as = vcycle_of_source(split.n, MPI_COMM_SELF, x_sides, {1, 1, 1}, &as_levels, nullptr,
                                                      2, nullptr, as_on);
      const std::vector<double> own = vcycle_of_source(split.n, MPI_COMM_SELF, x_sides, {1, 1, 1});
      const int as_iterations = iterations_on(split.n, MPI_COMM_SELF, x_sides, {1, 1, 1}, as_on);
      const int own_iterations = iterations_on(split.n, MPI_COMM_SELF, x_sides, {1, 1, 1});
      std::size_t differ = 0, first = 0, own_differ = 0;
      for (std::size_t c = 0; c < ranks.size(); ++c) {
        if (ranks[c] != as[c] && differ++ == 0) first = c;
        own_differ += ranks[c] != own[c] ? 1 : 0;
      }
      const std::string what = std::to_string(split.n[0]) + " x " + std::to_string(split.n[1]) + " x " +
                               std::to_string(split.n[2]) + " on " + std::to_string(size) + " ranks, x " +
                               boundary_name(x_sides);
      std::printf("%s: %d levels (%d gathered), CG iterations %d on the ranks, %d laid out as on them, %d one rank's own\n",
                  what.c_str(), levels, gathered, ranks_iterations, as_iterations, own_iterations);
      double worst = 0, scale = 0;
      for (std::size_t c = 0; c < ranks.size(); ++c) worst = std::max(worst, std::abs(ranks[c] - as[c])), scale = std::max(scale, std::abs(ranks[c]));
      EXPECT_EQ(differ, 0u) << what << ": first at cell " << first << ", " << as[first] << " against " << ranks[first] << " worst " << worst / scale;
      EXPECT_EQ(as_levels, levels) << what;
      EXPECT_EQ(as_iterations, ranks_iterations) << what;
      EXPECT_GT(own_differ, 0u) << what << ": one rank's own levels are the ranks' here; the test shows nothing";
    }
}

// Pairs over the whole level (`fluid.poisson.multigrid.pairs: level`): a pair across a cut belongs
// to the rank of its first cell, which takes the second's residual and coefficients from the
// neighbour, and the neighbour takes the pair's correction. The levels are one rank's where none is
// gathered, so the V-cycle is one rank's to the bit; where some are (blocks of a few cells), it is
// the one-process lay-out's of those cuts (levels_as_on), and CG's iterations are its. Cuts on odd
// cells along x, along y, and along both on 4 ranks (pairs across two cuts: a corner's), walls and
// x periodic; the blocks' own pairs give other numbers there (else the test would show nothing).
TEST(CellMultigrid, LevelPairsGiveOneRanksVCycleOnAnyCuts) {
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size == 1) return;
  struct Split {
    std::array<int, 3> n, procs;
  };
  std::vector<Split> splits{{{45, 45, 33}, {size, 1, 1}}, {{24, 46, 40}, {1, size, 1}}};
  if (size == 4) splits.push_back({{46, 46, 20}, {2, 2, 1}});
  for (const Split& split : splits)
    for (const BoundaryKind x_sides : {BoundaryKind::no_slip, BoundaryKind::periodic}) {
      if (x_sides == BoundaryKind::periodic && split.n[0] % 2) continue;
      LevelsAsOn as_on;
      as_on.grid = split.procs;
      const double box[3] = {kL, kL, 0.75 * kL};
      for (int d = 0; d < 3; ++d)
        for (int c = 1; c < split.procs[d]; ++c) as_on.cuts[d].push_back(box[d] * c / split.procs[d]);
      int levels = 0, gathered = 0;
      const std::vector<double> pairs = vcycle_of_source(split.n, MPI_COMM_WORLD, x_sides, split.procs, &levels,
                                                         &gathered, 2, nullptr, {}, true);
      const std::vector<double> blocks = vcycle_of_source(split.n, MPI_COMM_WORLD, x_sides, split.procs);
      const int ranks_iterations = iterations_on(split.n, MPI_COMM_WORLD, x_sides, split.procs, {}, true);
      if (rank != 0) continue;
      const std::vector<double> as = vcycle_of_source(split.n, MPI_COMM_SELF, x_sides, {1, 1, 1}, nullptr, nullptr, 2,
                                                      nullptr, as_on, true);
      const std::vector<double> one = vcycle_of_source(split.n, MPI_COMM_SELF, x_sides, {1, 1, 1});
      const int as_iterations = iterations_on(split.n, MPI_COMM_SELF, x_sides, {1, 1, 1}, as_on, true);
      const int one_iterations = iterations_on(split.n, MPI_COMM_SELF, x_sides, {1, 1, 1});
      std::size_t differ = 0, first = 0, one_differ = 0, blocks_differ = 0;
      for (std::size_t c = 0; c < pairs.size(); ++c) {
        if (pairs[c] != as[c] && differ++ == 0) first = c;
        one_differ += pairs[c] != one[c] ? 1 : 0;
        blocks_differ += pairs[c] != blocks[c] ? 1 : 0;
      }
      const std::string what = std::to_string(split.n[0]) + " x " + std::to_string(split.n[1]) + " x " +
                               std::to_string(split.n[2]) + " on " + std::to_string(size) + " ranks, x " +
                               boundary_name(x_sides);
      std::printf("%s: %d levels (%d gathered), CG iterations %d with level pairs, %d laid out on one process, %d one "
                  "rank's\n", what.c_str(), levels, gathered, ranks_iterations, as_iterations, one_iterations);
      EXPECT_EQ(differ, 0u) << what << ": first at cell " << first << ", " << pairs[first] << " against " << as[first];
      EXPECT_EQ(as_iterations, ranks_iterations) << what;
      if (gathered == 0) {
        EXPECT_EQ(one_differ, 0u) << what << ": no level gathered, the V-cycle should be one rank's";
        EXPECT_EQ(one_iterations, ranks_iterations) << what;
      }
      EXPECT_GT(blocks_differ, 0u) << what << ": the blocks' own pairs give the same numbers; the test shows nothing";
    }
  // With one ghost layer on every level (an exchange before each pass): the same numbers.
  const Split& split = splits.back();
  const std::vector<double> pairs = vcycle_of_source(split.n, MPI_COMM_WORLD, BoundaryKind::no_slip, split.procs,
                                                     nullptr, nullptr, 1, nullptr, {}, true);
  if (rank != 0) return;
  LevelsAsOn as_on;
  as_on.grid = split.procs;
  const double box[3] = {kL, kL, 0.75 * kL};
  for (int d = 0; d < 3; ++d)
    for (int c = 1; c < split.procs[d]; ++c) as_on.cuts[d].push_back(box[d] * c / split.procs[d]);
  const std::vector<double> as = vcycle_of_source(split.n, MPI_COMM_SELF, BoundaryKind::no_slip, {1, 1, 1}, nullptr,
                                                  nullptr, 1, nullptr, as_on, true);
  std::size_t differ = 0;
  for (std::size_t c = 0; c < pairs.size(); ++c) differ += pairs[c] != as[c] ? 1 : 0;
  EXPECT_EQ(differ, 0u) << "one ghost layer";
}

// The plan (fluid/multigrid_plan.hpp) lays out the levels of P ranks from the finest level's cuts
// alone, for the scaling model: its levels, gathered levels, two-layer levels and coarsest size are
// the multigrid's own, and its count of a V-cycle's exchanges (plus the operator's one) is what rank
// 0 (an owner on every level) makes. Odd sizes, periodic x, gathers along one and two directions,
// one-layer and two-layer levels, on 1, 2 and 4 ranks.
TEST(CellMultigrid, ThePlanLaysOutItsLevelsAndCountsTheExchangesACycleMakes) {
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  struct Case {
    std::array<int, 3> n, procs;
    BoundaryKind x_sides;
    int ghost_layers;
    bool level_pairs = false;
  };
  std::vector<Case> cases{{{45, 45, 33}, {0, 0, 0}, BoundaryKind::no_slip, 2},
                          {{45, 45, 33}, {0, 0, 0}, BoundaryKind::no_slip, 1},
                          {{32, 30, 30}, {0, 0, 0}, BoundaryKind::periodic, 2},
                          {{16, 48, 48}, {size, 1, 1}, BoundaryKind::no_slip, 2},
                          {{16, 48, 48}, {size, 1, 1}, BoundaryKind::periodic, 2},
                          {{64, 64, 40}, {1, size, 1}, BoundaryKind::no_slip, 2},
                          {{45, 45, 33}, {size, 1, 1}, BoundaryKind::no_slip, 2, true},
                          {{45, 45, 33}, {0, 0, 0}, BoundaryKind::no_slip, 1, true}};
  if (size == 4) cases.push_back({{8, 8, 96}, {2, 2, 1}, BoundaryKind::no_slip, 2});
  for (const Case& cs : cases) {
    Problem P(cs.n, MPI_COMM_WORLD, cs.x_sides, cs.procs);
    const FluidGrid& g = P.grid;
    CellMultigrid mg(g, 2, 2, 20, true, cs.ghost_layers, {}, cs.level_pairs);
    mg.set_coefficients(P.rho);
    DM dm = g.pressure_dm();
    PetscInt pm, pn, pp;
    DMDAGetInfo(dm, nullptr, nullptr, nullptr, nullptr, &pm, &pn, &pp, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr);
    const PetscInt* own[3];
    DMDAGetOwnershipRanges(dm, &own[0], &own[1], &own[2]);
    const PetscInt procs[3] = {pm, pn, pp};
    std::array<std::vector<int>, 3> blocks;
    for (int d = 0; d < 3; ++d) blocks[d].assign(own[d], own[d] + procs[d]);
    const auto plan = plan_multigrid(blocks, {g.periodic(0), g.periodic(1), g.periodic(2)}, cs.ghost_layers, cs.level_pairs);
    const auto exchanges = multigrid_exchanges(plan, 2, 2, 20, true);
    Vec x, y;
    DMCreateGlobalVector(dm, &x);
    VecDuplicate(x, &y);
    VecSet(x, 1.0);
    mg.apply(x, y);
    mg.apply_operator(x, y);
    VecDestroy(&x);
    VecDestroy(&y);
    const std::string name = std::to_string(cs.n[0]) + " x " + std::to_string(cs.n[1]) + " x " + std::to_string(cs.n[2]) +
                             " on " + std::to_string(pm) + " x " + std::to_string(pn) + " x " + std::to_string(pp) +
                             ", x " + boundary_name(cs.x_sides) + ", " + std::to_string(cs.ghost_layers) + " layers" +
                             (cs.level_pairs ? ", level pairs" : "");
    EXPECT_EQ(int(plan.size()), mg.levels()) << name;
    EXPECT_EQ(plan.back().cells(), mg.coarsest_cells()) << name;
    EXPECT_EQ(int(std::count_if(plan.begin(), plan.end(), [](const auto& L) { return L.gathered(); })), mg.gathered_levels())
        << name;
    if (rank != 0) continue;
    EXPECT_EQ(int(std::count_if(plan.begin(), plan.end(), [](const auto& L) { return L.layers == 2; })),
              mg.two_layer_levels()) << name;
    int planned = 0;
    for (int e : exchanges) planned += e;
    EXPECT_EQ(double(planned), mg.exchanges_per_cycle()) << name;
    if (size > 1) {
      EXPECT_GT(planned, 0) << name;
    }
  }
}

// Solves A p = b with the multigrid-preconditioned CG; returns the iterations and checks the
// 7-point equations' residual here.
int solve_and_check(std::array<int, 3> n, bool coarse_direct = true, bool single_reduction = false) {
  const Problem P(n);
  const FluidGrid& g = P.grid;
  PoissonSettings st;
  st.rtol = 1e-10;
  st.coarse_direct = coarse_direct;
  st.single_reduction = single_reduction;
  std::vector<double> b, p;
  const PoissonStats stats = solve_source(P, st, b, p);
  // The neighbours' pressures: a ghost exchange on the field layout.
  Vec global, local;
  DMCreateGlobalVector(g.field_dm(), &global);
  DMCreateLocalVector(g.field_dm(), &local);
  PetscScalar* a;
  VecGetArray(global, &a);
  std::size_t m = 0;
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) a[m++] = p[g.at(i, j, k)];
  VecRestoreArray(global, &a);
  DMGlobalToLocal(g.field_dm(), global, INSERT_VALUES, local);
  const PetscScalar* pl;
  VecGetArrayRead(local, &pl);
  const double area_over_h[3] = {g.h(1) * g.h(2) / g.h(0), g.h(0) * g.h(2) / g.h(1), g.h(0) * g.h(1) / g.h(2)};
  double r2 = 0, b2 = 0;
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) {
        const std::size_t c = g.at(i, j, k);
        const int idx[3] = {i, j, k};
        double ap = 0;
        for (int d = 0; d < 3; ++d)
          for (int side = 0; side < 2; ++side) {
            const bool edge = side == 0 ? idx[d] == 0 : idx[d] == g.cells()[d] - 1;
            const std::size_t nb = side == 0 ? c - g.stride(d) : c + g.stride(d);
            if (!edge)
              ap += area_over_h[d] / (0.5 * (P.rho[c] + P.rho[nb])) * (pl[c] - pl[nb]);
            else if (g.boundary(d, side) == BoundaryKind::outflow)
              ap += 2 * area_over_h[d] / P.rho[c] * pl[c];  // p = 0 on the face
          }
        r2 += (b[c] - ap) * (b[c] - ap);
        b2 += b[c] * b[c];
      }
  VecRestoreArrayRead(local, &pl);
  VecDestroy(&global);
  VecDestroy(&local);
  double sums[2] = {r2, b2}, total[2];
  MPI_Allreduce(sums, total, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_LT(std::sqrt(total[0] / total[1]), 2e-10) << n[0] << " x " << n[1] << " x " << n[2];
  return stats.iterations;
}

TEST(CellMultigrid, OddSizesConvergeAsFastAsEvenOnes) {
  const int odd = solve_and_check({45, 45, 33});
  const int even = solve_and_check({44, 44, 32});
  int rank;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) std::printf("CG iterations to 1e-10: 45 x 45 x 33 %d, 44 x 44 x 32 %d\n", odd, even);
  EXPECT_LE(odd, even + 2);
  EXPECT_LE(even, 30);
}

// The coarse face coefficients' distances (theory F9a): odd blocks end in single cells (a block of
// 9 gives widths 2, 2, 2, 2, 1 in finest cells, then 4, 5 where the single joins the pair before it),
// and gathered levels pair cells of unequal widths, so each coarse face's divisor must be
// the distance between the coarse centres over the fine centres' across it, both measured here from
// the levels' aggregates composed down to the finest cells (not from the plan's widths). Laid out
// on one process for the blocks of many ranks (the paper drop's 176 cells on 5, 10 and 20 ranks;
// walls and periodic), and no level's neighbouring cells differ in width by more than 2 (with pairs
// alone a block of 9 went on 4, 4, 1 and 8, 1). Until 2026-12-06 the divisor counted the next
// finer level's cells, right only where they are equal: the paper drop's CG took 8.33 iterations a
// flow step on 25 ranks and 9.0 on 100; 7.00 and 8.00 with the distances, 7.00 and 7.67 with the
// triples too (one rank: 6.67). Checked by mutation: the old divisor fails this 376 times, pairs
// alone 282 times.
TEST(CellMultigrid, CoarseFacesTakeTheDistanceBetweenCentresInFinestCells) {
  auto split = [](int n, int p) {
    std::vector<int> b;
    for (int r = 0; r < p; ++r) b.push_back((n * (r + 1)) / p - (n * r) / p);
    return b;
  };
  struct Case {
    std::array<std::vector<int>, 3> blocks;
    std::array<bool, 3> periodic;
  };
  const std::vector<Case> cases{{{split(176, 5), split(176, 5), split(128, 1)}, {false, false, false}},
                                {{split(176, 10), split(176, 10), split(128, 1)}, {false, false, false}},
                                {{split(176, 20), split(176, 20), split(128, 1)}, {false, false, false}},
                                {{split(45, 3), split(33, 1), split(96, 6)}, {false, false, false}},
                                {{split(64, 4), split(36, 2), split(40, 1)}, {true, false, false}}};
  int unequal = 0;
  for (const Case& cs : cases) {
    const auto plan = plan_multigrid(cs.blocks, cs.periodic, 2);
    ASSERT_GE(plan.size(), 4u);
    for (int d = 0; d < 3; ++d) {
      // Each level's cells as ranges of finest cells: begin[l][I] .. begin[l][I + 1].
      std::vector<std::vector<double>> begin{{}};
      for (int i = 0; i <= plan[0].n[d]; ++i) begin[0].push_back(i);
      for (std::size_t l = 1; l < plan.size(); ++l) {
        begin.emplace_back();
        for (int I = 0; I <= plan[l].n[d]; ++I) begin[l].push_back(begin[l - 1][std::size_t(plan[l].fine_start[d][std::size_t(I)])]);
      }
      const double N = plan[0].n[d];
      auto centre = [&](std::size_t l, int I) { return 0.5 * (begin[l][std::size_t(I)] + begin[l][std::size_t(I) + 1]); };
      for (std::size_t l = 1; l < plan.size(); ++l) {
        const int nc = plan[l].n[d], nf = plan[l - 1].n[d];
        if (nc == nf) continue;  // not coarsened along d
        std::set<double> widths;
        for (int I = 0; I < nc; ++I) widths.insert(begin[l][std::size_t(I) + 1] - begin[l][std::size_t(I)]);
        unequal += widths.size() > 1;
        // No cell is less than half as wide as its neighbour: an odd block's single cell joins the
        // pair before it once it is a sliver (with pairs alone a block of 9 goes on 4, 4, 1 and 8, 1).
        for (int I = 1; I < nc; ++I) {
          const double a = begin[l][std::size_t(I)] - begin[l][std::size_t(I) - 1], b = begin[l][std::size_t(I) + 1] - begin[l][std::size_t(I)];
          EXPECT_LE(std::max(a, b), 2 * std::min(a, b)) << "level " << l << ", direction " << d << ", cells " << I - 1 << ", " << I;
        }
        for (int I = 0; I <= nc; ++I) {
          const int i = plan[l].fine_start[d][std::size_t(I)];
          double coarse, fine;  // the centres' distances across the face (to it, at a wall)
          if (!cs.periodic[d] && (I == 0 || I == nc)) {
            coarse = I == 0 ? centre(l, 0) : N - centre(l, nc - 1);
            fine = I == 0 ? centre(l - 1, 0) : N - centre(l - 1, nf - 1);
          } else {
            coarse = I % nc == 0 ? centre(l, 0) + N - centre(l, nc - 1) : centre(l, I) - centre(l, I - 1);
            fine = i % nf == 0 ? centre(l - 1, 0) + N - centre(l - 1, nf - 1) : centre(l - 1, i) - centre(l - 1, i - 1);
          }
          EXPECT_DOUBLE_EQ(coarse_face_distance(plan[l - 1], plan[l], d, I, cs.periodic[d]), coarse / fine)
              << "level " << l << ", direction " << d << ", face " << I << " of " << nc;
        }
      }
    }
  }
  EXPECT_GT(unequal, 5);  // the cases have levels whose widths differ
}

// The coarsest level is solved exactly (LU, theory F9a): on a grid that is one level (216 cells,
// below the coarsening's 256), the preconditioner is the inverse of the V-cycle's operator, whose
// single-precision coefficients differ from the double operator CG iterates on by 1e-7: CG reaches
// 1e-10 in 2 iterations; 20 red-black sweeps instead take more. The V-cycle stays symmetric
// positive definite with the exact solve on several levels (checked above on 45 x 45 x 33).
TEST(CellMultigrid, TheCoarsestLevelIsSolvedExactly) {
  Problem P({6, 6, 6});
  CellMultigrid mg(P.grid);
  mg.set_coefficients(P.rho);
  EXPECT_EQ(mg.levels(), 1);
  const int direct = solve_and_check({6, 6, 6}, true), sweeps = solve_and_check({6, 6, 6}, false);
  int rank;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) std::printf("one level: CG iterations to 1e-10 %d with LU, %d with 20 sweeps\n", direct, sweeps);
  EXPECT_LE(direct, 2);
  EXPECT_GT(sweeps, direct);
}

// CG with its two inner products in one reduction (fluid.poisson.single_reduction, theory F9)
// reaches the same 7-point residual (checked in solve_and_check) in the same iterations, give or take
// one (the recurrences round differently).
TEST(CellMultigrid, SingleReductionCGConvergesAsTheStandardOne) {
  const int standard = solve_and_check({44, 44, 32}, true, false);
  const int single = solve_and_check({44, 44, 32}, true, true);
  int rank;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) std::printf("CG iterations to 1e-10, 44 x 44 x 32: %d standard, %d with one reduction\n", standard, single);
  EXPECT_LE(std::abs(single - standard), 1);
}

}  // namespace
