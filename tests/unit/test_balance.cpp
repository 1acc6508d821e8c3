// SPDX-License-Identifier: MIT
// Balanced cut planes (core/balance.hpp, issue 19): the cut search equalises a known cost field to
// within one cell layer, respects the slabs' smallest width and the cell faces, and balances a bed
// that fills the bottom of a box where equal slabs leave the top ranks idle. The blast's levelled
// sub-steps: a macro step's time from the per-level work, counted by hand.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>

#include "core/balance.hpp"
#include "fracture/element_partition.hpp"

using namespace tessera;

// Cost per cell layer along z falling as exp(-z / 0.15) over 64 layers of a unit box (the work of a
// bed that thins upwards), one sample per cell centre: 4 slabs on cell faces. Each slab's cost is
// within one cell layer's cost of the mean (the best a cell-aligned cut can do), and the cuts lie
// on cell faces.
TEST(Balance, EqualisesAKnownCostFieldToOneCellLayer) {
  const int n = 64;
  const double h = 1.0 / n;
  std::vector<double> x, w;
  double total = 0;
  for (int k = 0; k < n; ++k) {
    const double z = (k + 0.5) * h, cost = std::exp(-z / 0.15);
    for (int s = 0; s < 8; ++s) x.push_back(z), w.push_back(cost / 8);  // 8 cells per layer
    total += cost;
  }
  const auto cuts = balanced_cuts(x, w, 0.0, 1.0, 4, 2 * h, h);
  ASSERT_EQ(cuts.size(), 3u);
  std::vector<double> slab(4, 0.0);
  for (std::size_t i = 0; i < x.size(); ++i) {
    int c = 0;
    while (c < 3 && x[i] >= cuts[c]) ++c;
    slab[c] += w[i];
  }
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(cuts[c] / h, std::round(cuts[c] / h), 1e-9) << "on a cell face";
  // A slab may be off by the layer at each of its cuts (a cut moves by at most one layer from the
  // ideal position when it goes to a cell face).
  auto layer_at = [&](double cut) {  // the heavier of the two layers that meet at the cut
    const int k = int(std::round(cut / h));
    return std::max(std::exp(-(k - 0.5) * h / 0.15), std::exp(-(k + 0.5) * h / 0.15));
  };
  for (int c = 0; c < 4; ++c) {
    const double allowed = (c > 0 ? layer_at(cuts[c - 1]) : 0.0) + (c < 3 ? layer_at(cuts[c]) : 0.0);
    std::printf("slab %d: cost %.4f of mean %.4f (the layers at its cuts %.4f)\n", c, slab[c], total / 4, allowed);
    EXPECT_LE(std::abs(slab[c] - total / 4), allowed) << c;
  }
  // Equal slabs put most of the work in the lowest.
  std::vector<double> equal(4, 0.0);
  for (std::size_t i = 0; i < x.size(); ++i) equal[std::min(3, int(x[i] * 4))] += w[i];
  EXPECT_GT(imbalance(equal), 2.0);
  EXPECT_LT(imbalance(slab), 1.1);
}

// A bed of bodies filling the bottom 30 % of a box on a 2 x 2 x 2 grid: equal slabs leave the four
// upper ranks without work (imbalance 2); balanced cuts share it (a lattice: exact up to a row).
TEST(Balance, ABedInTheBottomOfABox) {
  std::vector<WorkSample> bed;
  for (int k = 0; k < 15; ++k)
    for (int j = 0; j < 50; ++j)
      for (int i = 0; i < 50; ++i) bed.push_back({{(i + 0.5) / 50, (j + 0.5) / 50, (k + 0.5) / 50}, 1.0});
  const Vec3 lo{0, 0, 0}, hi{1, 1, 1};
  const std::array<int, 3> dims{2, 2, 2};
  const double equal = imbalance(rank_work(bed, dims, equal_cuts(lo, hi, dims)));
  const CutPlanes cuts = balanced_cuts(bed, lo, hi, dims);
  const double balanced = imbalance(rank_work(bed, dims, cuts));
  std::printf("bed in the bottom 30 %%, 2x2x2: imbalance %.3f with equal slabs, %.3f balanced (z cut %.4f)\n", equal,
              balanced, cuts[2][0]);
  EXPECT_DOUBLE_EQ(equal, 2.0);
  EXPECT_LT(balanced, 1.0 + 2.0 / 15);  // one row of 15 in z at most
  EXPECT_NEAR(cuts[0][0], 0.5, 1e-12);  // x and y: uniform, the middle
  EXPECT_NEAR(cuts[2][0], 0.15, 1.0 / 50);
}

// All the work at one point: the cuts still leave every slab its smallest width, inside the box.
TEST(Balance, SlabsKeepTheirSmallestWidth) {
  const std::vector<double> x(100, 0.5), w(100, 1.0);
  const auto cuts = balanced_cuts(x, w, 0.0, 1.0, 4, 0.2);
  ASSERT_EQ(cuts.size(), 3u);
  double prev = 0.0;
  for (const double c : cuts) {
    EXPECT_GE(c - prev, 0.2 - 1e-12);
    prev = c;
  }
  EXPECT_GE(1.0 - prev, 0.2 - 1e-12);
  EXPECT_THROW(balanced_cuts(x, w, 0.0, 1.0, 6, 0.2), std::invalid_argument);
}

// No work: equal slabs.
TEST(Balance, NoWorkGivesEqualSlabs) {
  const auto cuts = balanced_cuts({}, {}, 0.0, 3.0, 3);
  ASSERT_EQ(cuts.size(), 2u);
  EXPECT_DOUBLE_EQ(cuts[0], 1.0);
  EXPECT_DOUBLE_EQ(cuts[1], 2.0);
}

// Three levels on two ranks, the work per sub-step kind [f][rank]: all due [2, 2], levels 1-2 due
// [1, 1], level 2 alone [1, 0]. A macro step is 4 sub-steps: j = 1, 3 (level 2 alone, the busiest
// rank 1 each), j = 2 (1), j = 4 (2): 5 against the means' 0.5 + 1 + 0.5 + 2 = 4.
TEST(Balance, SubStepsWaitForTheirBusiestRank) {
  const std::vector<std::vector<double>> work = {{2, 2}, {1, 1}, {1, 0}};
  EXPECT_DOUBLE_EQ(substep_time(work), 5.0);
  EXPECT_DOUBLE_EQ(substep_imbalance(work), 1.25);
  const std::vector<double> rows = level_imbalance(work);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_DOUBLE_EQ(rows[0], 1.0);
  EXPECT_DOUBLE_EQ(rows[2], 2.0);
  // One level: the macro step's own imbalance.
  EXPECT_DOUBLE_EQ(substep_imbalance({{3, 1}}), 1.5);
}

namespace tessera {
namespace {

// The blast's halo per sub-step kind: four elements on two parts {0, 0, 1, 1} at levels {0, 2, 1, 0},
// bonds 0-1 (inside part 0), 1-2, 1-3 and 0-2 (across). Part 0 sends element 1 (level 2: after
// kinds 0, 1, 2) and element 0 (kind 0); part 1 sends element 2 (kinds 0, 1) and element 3 (kind 0),
// each once however many of its bonds cross.
TEST(Balance, TheHaloSendsEachCrossingElementOncePerKindItIsDue) {
  BondedBlock block;
  for (const auto& [m, s] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{1, 3}, std::pair{0, 2}}) {
    BondGeometry g;
    g.master = m, g.slave = s;
    block.bonds.push_back(g);
  }
  ElementWork work;
  work.level = {0, 2, 1, 0};
  const LevelHalo h = part_level_halo(block, work, {0, 0, 1, 1}, 2);
  ASSERT_EQ(h.sent.size(), 3u);
  EXPECT_EQ(h.sent[0], (std::vector<double>{2, 2}));
  EXPECT_EQ(h.sent[1], (std::vector<double>{1, 1}));
  EXPECT_EQ(h.sent[2], (std::vector<double>{1, 0}));
  EXPECT_EQ(h.neighbours, (std::vector<int>{1, 1}));
}

// A chain of elements 0-1-...-(n-1), bonded to their next, at the given levels.
BondedBlock chain(std::size_t n) {
  BondedBlock block;
  block.mass.assign(n, 1.0);
  block.x0.assign(n, Vec3{});
  for (std::size_t e = 0; e + 1 < n; ++e) {
    BondGeometry g;
    g.master = int(e), g.slave = int(e + 1);
    block.bonds.push_back(g);
  }
  return block;
}

// One level, six elements in a chain, five on part 0 and the last on part 1: part 0 does 5 updates
// and 5 bonds (the cut one on both parts), 5 + 5 x 1.4 = 12, part 1 1 + 1.4 = 2.4. The refinement
// moves element 4 (9.6 against 4.8), then element 3: three a part, 3 + 3 x 1.4 = 7.2 each, the
// best two parts can do; then no move shortens the step.
TEST(Balance, RefinementEvensAChainsParts) {
  const BondedBlock block = chain(6);
  const ElementWork work = element_work(block, std::vector<int>(6, 0));
  std::vector<int> part = {0, 0, 0, 0, 0, 1};
  EXPECT_NEAR(substep_time(part_level_work(block, work, part, 2)), 12.0, 1e-12);
  refine_by_substeps(block, work, part, 2);
  EXPECT_EQ(part, (std::vector<int>{0, 0, 0, 1, 1, 1}));
  EXPECT_NEAR(substep_time(part_level_work(block, work, part, 2)), 7.2, 1e-12);
}

// Two levels: a chain of 8, the first four at level 1 (element 4 too, by its bond with 3), two parts,
// six elements on part 0: rows 14.4 / 4.8 and 10.6 / 0, a step of 25.0. The refinement ends where
// no move of an element to a part it is bonded to shortens the step (each tried here), 19.2, with
// no part empty. It is a local search that keeps parts joined: the shortest step of all 254
// partitions with both parts used is 18.2 ({0,0,0,1,1,0,1,1}, rows 11.0 / 11.0 and 7.2 / 4.8), with
// element 5 an island in part 0, which it does not make.
TEST(Balance, RefinementEndsWhereNoMoveShortensTheStep) {
  const BondedBlock block = chain(8);
  const ElementWork work = element_work(block, {1, 1, 1, 1, 0, 0, 0, 0});
  auto step = [&](const std::vector<int>& p) { return substep_time(part_level_work(block, work, p, 2)); };
  std::vector<int> part = {0, 0, 0, 0, 0, 0, 1, 1};
  EXPECT_NEAR(step(part), 25.0, 1e-12);
  refine_by_substeps(block, work, part, 2);
  EXPECT_NEAR(step(part), 19.2, 1e-12);
  const auto used = std::count(part.begin(), part.end(), 0);
  EXPECT_TRUE(used > 0 && used < 8);
  int tried = 0;
  for (std::size_t e = 0; e < 8; ++e) {
    const bool linked = (e > 0 && part[e - 1] != part[e]) || (e < 7 && part[e + 1] != part[e]);
    if (!linked) continue;
    std::vector<int> moved = part;
    moved[e] = 1 - moved[e];
    EXPECT_GE(step(moved), step(part) - 1e-12) << "moving element " << e;
    ++tried;
  }
  EXPECT_GE(tried, 2);
  double best = 1e300;
  for (int mask = 1; mask < 255; ++mask) {
    std::vector<int> p(8);
    for (int e = 0; e < 8; ++e) p[std::size_t(e)] = (mask >> e) & 1;
    best = std::min(best, step(p));
  }
  EXPECT_NEAR(best, 18.2, 1e-12);
}

}  // namespace
}  // namespace tessera

// A flow rank's cells enter the cut search as one box of uniform work (the flow and coupled scenes'
// balance), not a sample per cell. Two boxes along x, [0, 1/4] of work 3 and [1/4, 1] of work 1, on
// 2 slabs with cuts on the faces of 64 cells: half the work lies left of x = 1/6, so the cut is the
// face next to it, and it is the cut that a sample per cell centre gives.
TEST(Balance, ABoxOfCellsWeighsAsItsCells) {
  const std::vector<WorkBox> boxes = {{{0, 0, 0}, {0.25, 1, 1}, 3.0}, {{0.25, 0, 0}, {1, 1, 1}, 1.0}};
  const Vec3 lo{0, 0, 0}, hi{1, 1, 1}, spacing{1.0 / 64, 1.0 / 64, 1.0 / 64};
  const auto from_boxes = balanced_cuts(MPI_COMM_SELF, {}, lo, hi, {2, 1, 1}, {}, spacing, 4096, boxes);
  std::vector<WorkSample> cells;
  for (int i = 0; i < 64; ++i) {
    const double x = (i + 0.5) / 64;
    cells.push_back({{x, 0.5, 0.5}, x < 0.25 ? 3.0 / 16 : 1.0 / 48});
  }
  const auto from_cells = balanced_cuts(MPI_COMM_SELF, cells, lo, hi, {2, 1, 1}, {}, spacing);
  ASSERT_EQ(from_boxes[0].size(), 1u);
  std::printf("cut from the boxes %.6f, from the cells %.6f (ideal 1/6 = %.6f)\n", from_boxes[0][0], from_cells[0][0],
              1.0 / 6);
  EXPECT_LE(std::abs(from_boxes[0][0] - 1.0 / 6), 1.0 / 64);
  EXPECT_NEAR(from_boxes[0][0] * 64, std::round(from_boxes[0][0] * 64), 1e-9);
  EXPECT_EQ(from_boxes[0][0], from_cells[0][0]);
  EXPECT_TRUE(from_boxes[1].empty() && from_boxes[2].empty());
}

// Two stages that each wait for their busiest rank, 2 ranks along x of a unit box on 1/64 cell
// faces: the cells (stage A) fill the box evenly, weight 1; the bodies' work (stage B), weight 1,
// fills x < 1/2 evenly (64 samples). By hand: the summed work's cut is at 1/3 (x + 2x = 1), where
// the stages' busiest ranks hold 2/3 + 2/3 against means 1/2 + 1/2: 1.333; the cells' own cut 1/2
// gives 1/2 + 1 (1.5); the bodies' own cut 1/4 gives 3/4 + 1/2 (1.25), the least of all cuts:
// max(x, 1 - x) + max(2x, 1 - 2x), with means 1/2 + 1/2, is least at x = 1/4.
TEST(Balance, StagedWorkTakesTheCutsWhoseBusiestRanksSumLeast) {
  const Vec3 lo{0, 0, 0}, hi{1, 1, 1}, spacing{1.0 / 64, 1.0 / 64, 1.0 / 64};
  StageWork cells{{}, {WorkBox{lo, hi, 1.0}}}, bodies;
  for (int i = 0; i < 64; ++i) bodies.samples.push_back({{(i + 0.5) / 128, 0.5, 0.5}, 1.0 / 64});
  const CutPlanes third{{{1.0 / 3}, {}, {}}};
  const auto summed = rank_work(MPI_COMM_SELF, cells, lo, hi, {2, 1, 1}, third);
  EXPECT_NEAR(summed[0], 1.0 / 3, 1e-12);  // the box shared by volume
  const StagedCuts best = staged_cuts(MPI_COMM_SELF, {cells, bodies}, lo, hi, {2, 1, 1}, {}, spacing);
  ASSERT_EQ(best.cuts[0].size(), 1u);
  std::printf("staged cut %.6f (%s), staged imbalance %.4f\n", best.cuts[0][0], best.candidate.c_str(), best.imbalance);
  EXPECT_NEAR(best.cuts[0][0], 0.25, 1e-12);
  EXPECT_NEAR(best.imbalance, 1.25, 1e-9);
  EXPECT_EQ(best.candidate, "stage 1");  // the bodies' own cuts
  // Cuts now that cost as little are kept.
  const CutPlanes now{{{0.25}, {}, {}}};
  EXPECT_EQ(staged_cuts(MPI_COMM_SELF, {cells, bodies}, lo, hi, {2, 1, 1}, {}, spacing, 4096, &now).candidate, "current");
  // The summed work's cut, as balanced_cuts gives it, costs more.
  StageWork both = bodies;
  both.boxes = cells.boxes;
  const auto sum_cuts = balanced_cuts(MPI_COMM_SELF, both.samples, lo, hi, {2, 1, 1}, {}, spacing, 4096, both.boxes);
  const double at_sum = staged_imbalance({rank_work(MPI_COMM_SELF, cells, lo, hi, {2, 1, 1}, sum_cuts),
                                          rank_work(MPI_COMM_SELF, bodies, lo, hi, {2, 1, 1}, sum_cuts)});
  std::printf("the summed work's cut %.6f: staged imbalance %.4f\n", sum_cuts[0][0], at_sum);
  EXPECT_NEAR(sum_cuts[0][0], 1.0 / 3, 1.0 / 64);
  EXPECT_GT(at_sum, 1.3);
  EXPECT_DOUBLE_EQ(staged_imbalance({{1, 1}, {2, 0}}), 3.0 / 2.0);
}

// Equal slabs of whole cells in blocks of 2^k cells (cell_block_cuts): the paper drop's 176 cells
// over 5, 10 and 20 ranks by hand (4-cell blocks, 2-cell blocks, none: 2-cell blocks would make a
// 10-cell slab where equal slabs make 9); and over a sweep of rows and rank counts the largest slab
// never exceeds ceil(cells / parts) and the smallest is at least equal slabs' smallest
// (floor(cells / parts)) or 0.9 of the mean.
TEST(Balance, CellBlocksAreAsLargeAsEqualSlabsAndHalveEvenly) {
  auto blocks = [](int cells, int parts) {
    const auto cuts = cell_block_cuts(0.0, 1.0, cells, parts);
    std::vector<int> b;
    double prev = 0;
    for (const double c : cuts) b.push_back(int(std::lround((c - prev) * cells))), prev = c;
    b.push_back(int(std::lround((1.0 - prev) * cells)));
    return b;
  };
  EXPECT_EQ(blocks(176, 5), (std::vector<int>{32, 36, 36, 36, 36}));
  EXPECT_EQ(blocks(176, 10), (std::vector<int>{16, 18, 18, 18, 18, 16, 18, 18, 18, 18}));
  for (const int b : blocks(176, 20)) EXPECT_TRUE(b == 8 || b == 9) << b;
  for (int cells = 8; cells <= 260; cells += 6)
    for (int parts = 2; parts <= cells / 2; parts += 3) {
      const auto b = blocks(cells, parts);
      ASSERT_EQ(int(b.size()), parts);
      int sum = 0, most = 0, least = cells;
      for (const int x : b) sum += x, most = std::max(most, x), least = std::min(least, x);
      EXPECT_EQ(sum, cells);
      EXPECT_LE(most, (cells + parts - 1) / parts) << cells << " / " << parts;
      EXPECT_TRUE(least >= cells / parts || 10 * least >= 9 * cells / parts) << cells << " / " << parts;
    }
}
