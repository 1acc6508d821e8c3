// SPDX-License-Identifier: MIT
// The liquid in the cells' fluid part (src/coupling/pore_liquid.hpp, theory C7) on 1, 2 and 4 ranks,
// the ranks cutting the x axis along which everything moves:
//  - a liquid column driven at speed u into a porous region of fluid part e = 0.5: the front there
//    advances at u / e (the pores fill; with the liquid fraction advected over whole cells it would
//    advance at u), the pores behind it are full, the liquid volume changes by the inflow only;
//  - a solid block moved through a box full of liquid, one cell per step: the liquid it displaces
//    refills the cells it leaves, so that every cell ends full (c = e), the volume unchanged; the
//    same block moved out of liquid into gas: the volume unchanged, every cell within [0, e];
//  - the same numbers, bit for bit, on one rank holding the whole grid.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "core/decomposition.hpp"
#include "coupling/pore_liquid.hpp"
#include "fluid/flow_solver.hpp"

namespace tessera::test {
namespace {

bool root() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank == 0;
}

constexpr int kNx = 48, kNt = 4;  // 48 x 4 x 4 cells over 1 x 1/12 x 1/12: cubes of 1/48

FlowSettings column() {
  FlowSettings st;
  st.cells = {kNx, kNt, kNt};
  st.boundaries = {{{BoundaryKind::outflow, BoundaryKind::outflow},
                    {BoundaryKind::free_slip, BoundaryKind::free_slip},
                    {BoundaryKind::free_slip, BoundaryKind::free_slip}}};
  st.gravity = {};
  st.liquid.viscosity = st.gas.viscosity = 0;
  return st;
}

// A ghosted solid-fraction field from a function of the global cell index i along x (ghosts beyond
// the domain take the nearest cell's value, as the coupling's would not matter there).
std::vector<double> solid(const FluidGrid& g, const std::function<double(int)>& alpha_of_i) {
  std::vector<double> a = g.make_field();
  for (std::size_t c = 0; c < a.size(); ++c) a[c] = alpha_of_i(std::clamp(g.index(c)[0], 0, kNx - 1));
  return a;
}

// The liquid content along x (owned cells of row j = k = 0 that this rank holds), gathered on every
// rank.
std::vector<double> row(const FluidGrid& g, const std::vector<double>& field) {
  std::vector<double> r(kNx, -1e300);
  if (g.begin(1) == 0 && g.begin(2) == 0)
    for (int i = g.begin(0); i < g.end(0); ++i) r[i] = field[g.at(i, 0, 0)];
  MPI_Allreduce(MPI_IN_PLACE, r.data(), kNx, MPI_DOUBLE, MPI_MAX, g.comm());
  return r;
}

struct FrontResult {
  double front = 0, volume0 = 0, volume1 = 0, min_c = 0, max_over = 0;
  std::vector<double> content;
  int passes = 0;
};

// Liquid for x < 0.25 moving at u = 1 along x; e = 0.5 for x > 0.5. 84 steps of s = u dt / h = 0.25
// to t = 0.4375: the front reached x = 0.5 at t = 0.25 and is at 0.5 + (t - 0.25) / e = 0.875.
// `barrier`: cells i = 32, 33 (x in [2/3, 17/24)) have e = 0.05 instead, where the flow carries more
// liquid in than they hold: the settle passes move it on. Then the front is 2 x 0.45 h further.
double porous_alpha(int i, bool barrier) {
  if (barrier && (i == 32 || i == 33)) return 0.95;
  return i >= kNx / 2 ? 0.5 : 0.0;
}

FrontResult porous_front(MPI_Comm comm, bool barrier) {
  Decomposition decomp(comm, {0, 0, 0}, {1.0, 1.0 / 12, 1.0 / 12}, {0, 1, 1});
  FlowSolver flow(decomp, column());
  const FluidGrid& g = flow.grid();
  flow.initialize([&](int i, int, int) { return FlowSolver::CellState{i < kNx / 4 ? 1.0 : 0.0, {}}; });
  const std::vector<double> alpha = solid(g, [barrier](int i) { return porous_alpha(i, barrier); });
  auto& uf = flow.mutable_face_velocity(0);
  std::fill(uf.begin(), uf.end(), 1.0);
  for (int d = 1; d < 3; ++d) std::fill(flow.mutable_face_velocity(d).begin(), flow.mutable_face_velocity(d).end(), 0.0);
  PoreLiquid liquid(g);
  liquid.start(flow, alpha);
  liquid.settle(flow, alpha);
  FrontResult r;
  r.volume0 = liquid.volume();
  const double h = 1.0 / kNx, dt = 0.25 * h;
  for (int n = 0; n < 84; ++n) {
    liquid.before_flow(flow);
    flow.advect(dt);
    liquid.after_flow(flow);
    r.passes = std::max(r.passes, liquid.settle(flow, alpha).passes);
  }
  r.volume1 = liquid.volume();
  const std::vector<double> phi = row(g, flow.fraction()), c = row(g, liquid.content());
  r.content = c;
  // The front: where the liquid share of the fluid part crosses 1/2 (linear between cell centres).
  for (int i = kNx / 2; i + 1 < kNx; ++i)
    if (phi[i] >= 0.5 && phi[i + 1] < 0.5) r.front = (i + 0.5 + (phi[i] - 0.5) / (phi[i] - phi[i + 1])) * h;
  double lo = 1, over = -1;
  for (int i = 0; i < kNx; ++i) {
    const double e = 1 - porous_alpha(i, barrier);
    lo = std::min(lo, c[i]);
    over = std::max(over, c[i] - e);
  }
  r.min_c = lo, r.max_over = over;
  return r;
}

TEST(PoreLiquid, FrontAdvancesAtSpeedOverPorosity) {
  const FrontResult r = porous_front(MPI_COMM_WORLD, false);
  const double h = 1.0 / kNx, t = 84 * 0.25 * h;
  if (root())
    std::printf("porous front at %.5f (u / e: %.5f; whole cells would give %.5f), volume %.15g -> %.15g "
                "(inflow %.15g), passes %d\n",
                r.front, 0.5 + (t - 0.25) / 0.5, 0.5 + (t - 0.25), r.volume0, r.volume1, t / 144.0, r.passes);
  EXPECT_NEAR(r.front, 0.5 + (t - 0.25) / 0.5, 1.5 * h);
  // The pores behind the front are full: c = e.
  for (int i = kNx / 2 + 1; i < int((0.5 + (t - 0.25) / 0.5) / h) - 2; ++i) EXPECT_NEAR(r.content[i], 0.5, 1e-9) << i;
  // Inflow through x = 0 at u = 1 over the face 1/12 x 1/12, the outflow face not reached.
  EXPECT_NEAR(r.volume1 - r.volume0, t / 144.0, 1e-12 * r.volume1);
  EXPECT_GT(r.min_c, -1e-12);
  EXPECT_LT(r.max_over, 1e-12);
  // One rank holding the whole grid: the same bits.
  const FrontResult s = porous_front(MPI_COMM_SELF, false);
  for (int i = 0; i < kNx; ++i) EXPECT_EQ(r.content[i], s.content[i]) << i;
}

TEST(PoreLiquid, LiquidCarriedIntoNearlySolidCellsMovesOn) {
  const FrontResult r = porous_front(MPI_COMM_WORLD, true);
  const double h = 1.0 / kNx, t = 84 * 0.25 * h, expected = 0.5 + (t - 0.25) / 0.5 + 2 * 0.45 * h / 0.5;
  if (root())
    std::printf("front past a barrier of e = 0.05: %.5f (expected %.5f), largest excursion out of [0, e] %.2e, "
                "passes per step <= %d\n",
                r.front, expected, std::max(-r.min_c, r.max_over), r.passes);
  EXPECT_GT(r.passes, 0);  // the stage is exercised
  EXPECT_NEAR(r.front, expected, 1.5 * h);
  EXPECT_NEAR(r.volume1 - r.volume0, t / 144.0, 1e-12 * r.volume1);
  EXPECT_GT(r.min_c, -PoreLiquid::kTolerance);
  EXPECT_LT(r.max_over, PoreLiquid::kTolerance);
  const FrontResult s = porous_front(MPI_COMM_SELF, true);
  for (int i = 0; i < kNx; ++i) EXPECT_EQ(r.content[i], s.content[i]) << i;
}

// A solid block of 3 x 4 x 4 cells, alpha = 0.9, moved one cell along x per step through a box full
// of liquid from i = 8 to i = 38: the liquid it displaces must end in the cells it left.
// `wet`: the cells i < wet hold liquid, the others gas (48: all liquid).
std::vector<double> moving_block(MPI_Comm comm, int wet, double& drift, double& worst, int& passes) {
  Decomposition decomp(comm, {0, 0, 0}, {1.0, 1.0 / 12, 1.0 / 12}, {0, 1, 1});
  FlowSettings st = column();
  st.boundaries[0] = {BoundaryKind::free_slip, BoundaryKind::free_slip};
  FlowSolver flow(decomp, st);
  const FluidGrid& g = flow.grid();
  flow.initialize([&](int i, int, int) { return FlowSolver::CellState{i < wet ? 1.0 : 0.0, {}}; });
  auto block_at = [&](int first) { return solid(g, [first](int i) { return i >= first && i < first + 3 ? 0.9 : 0.0; }); };
  PoreLiquid liquid(g);
  std::vector<double> alpha = block_at(8);
  liquid.start(flow, alpha);
  liquid.settle(flow, alpha);
  const double v0 = liquid.volume();
  passes = 0;
  for (int first = 9; first <= 38; ++first) {
    const std::vector<double> before = alpha;
    alpha = block_at(first);
    liquid.before_flow(flow);
    liquid.after_flow(flow);  // no flow: the block alone moves the liquid
    // The block as one body: its change of volume in each owned cell; its sums over all ranks.
    BodyMoves moves;
    for (int k = g.begin(2); k < g.end(2); ++k)
      for (int j = g.begin(1); j < g.end(1); ++j)
        for (int i = g.begin(0); i < g.end(0); ++i) {
          const std::size_t c = g.at(i, j, k);
          if (alpha[c] != before[c]) moves.cell.push_back(c), moves.dv.push_back((alpha[c] - before[c]) * g.cell_volume());
        }
    moves.body.push_back(0);
    moves.first.push_back(moves.cell.size());
    liquid.displace(moves, 1, [&](std::vector<double>& sums) {
      MPI_Allreduce(MPI_IN_PLACE, sums.data(), int(sums.size()), MPI_DOUBLE, MPI_SUM, comm);
    });
    passes = std::max(passes, liquid.settle(flow, alpha).passes);
  }
  drift = (liquid.volume() - v0) / v0;
  worst = 0;
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) {
        const std::size_t c = g.at(i, j, k);
        const double e = 1 - alpha[c], cc = liquid.content()[c];
        worst = std::max(worst, wet == kNx ? std::abs(cc - e) : std::max(cc - e, -cc));
      }
  worst = g.reduce_max(worst);
  return row(g, liquid.content());
}

TEST(PoreLiquid, MovingBlockDisplacesAndRefills) {
  double drift = 0, worst = 0;
  int passes = 0;
  const std::vector<double> c = moving_block(MPI_COMM_WORLD, kNx, drift, worst, passes);
  if (root()) std::printf("moving block: volume drift %.3e, largest |c - e| %.3e, passes per step <= %d\n", drift, worst, passes);
  EXPECT_LT(std::abs(drift), 1e-14);
  EXPECT_LT(worst, 1e-11);
  EXPECT_LT(passes, PoreLiquid::kMaxPasses);
  double d1 = 0, w1 = 0;
  int p1 = 0;
  const std::vector<double> s = moving_block(MPI_COMM_SELF, kNx, d1, w1, p1);
  for (int i = 0; i < kNx; ++i) EXPECT_EQ(c[i], s[i]) << i;
  // From liquid (i < 20) into gas: the liquid volume is kept, no cell leaves [0, e].
  const std::vector<double> w = moving_block(MPI_COMM_WORLD, 20, drift, worst, passes);
  if (root()) std::printf("block leaving the liquid: volume drift %.3e, largest excursion out of [0, e] %.3e\n", drift, worst);
  EXPECT_LT(std::abs(drift), 1e-14);
  EXPECT_LT(worst, 1e-12);
  // The liquid left behind the block: the cells it passed through in the liquid (e = 1 again) are
  // full, the ones beyond it hold none.
  for (int i = 0; i < 8; ++i) EXPECT_NEAR(w[i], 1.0, 1e-12) << i;
}

}  // namespace
}  // namespace tessera::test
