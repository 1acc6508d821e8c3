// SPDX-License-Identifier: MIT
// The flow's ghost exchange (fluid/cell_halo.hpp) against PETSc's DMDA DMLocalToLocal, which it
// replaced, on 1, 2 and 4 ranks: odd block sizes, walls and periodic directions (two ranks along a
// periodic direction make both neighbours one rank), the box stencil two layers deep (the fields)
// and the star stencil one deep (the multigrid). Every owned cell holds a number made from its
// global index, every ghost a sentinel; after both exchanges the arrays must be equal in every
// entry, and every ghost the DMDA fills must hold the number of the (periodic) cell it images. A
// round sends one message to each neighbour rank, all fields in it.
#include <gtest/gtest.h>
#include <mpi.h>
#include <petscdmda.h>

#include <algorithm>
#include <array>
#include <vector>

#include "fluid/cell_halo.hpp"

using namespace tessera;

namespace {

constexpr double kSentinel = -1.0;

double label(int i, int j, int k) { return 1 + i + 100.0 * j + 10000.0 * k; }

struct Case {
  std::array<bool, 3> periodic;
  bool box;
  int width;
};

void check_case(const Case& cs) {
  const std::array<int, 3> n{9, 7, 6};
  DMBoundaryType bt[3];
  for (int d = 0; d < 3; ++d) bt[d] = cs.periodic[d] ? DM_BOUNDARY_PERIODIC : DM_BOUNDARY_GHOSTED;
  DM da;
  ASSERT_EQ(DMDACreate3d(MPI_COMM_WORLD, bt[0], bt[1], bt[2], cs.box ? DMDA_STENCIL_BOX : DMDA_STENCIL_STAR, n[0],
                         n[1], n[2], PETSC_DECIDE, PETSC_DECIDE, PETSC_DECIDE, 1, cs.width, nullptr, nullptr, nullptr,
                         &da),
            0);
  ASSERT_EQ(DMSetUp(da), 0);
  PetscInt pm, pn, pp, xs, ys, zs, xm, ym, zm, gxs, gys, gzs, gxm, gym, gzm;
  DMDAGetInfo(da, nullptr, nullptr, nullptr, nullptr, &pm, &pn, &pp, nullptr, nullptr, nullptr, nullptr, nullptr,
              nullptr);
  DMDAGetCorners(da, &xs, &ys, &zs, &xm, &ym, &zm);
  DMDAGetGhostCorners(da, &gxs, &gys, &gzs, &gxm, &gym, &gzm);
  int rank;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  CellHalo::Block b;
  b.procs = {int(pm), int(pn), int(pp)};
  b.coords = {rank % int(pm), (rank / int(pm)) % int(pn), rank / int(pm * pn)};
  b.periodic = cs.periodic;
  b.s = {int(xs), int(ys), int(zs)};
  b.m = {int(xm), int(ym), int(zm)};
  b.gs = {int(gxs), int(gys), int(gzs)};
  b.gm = {int(gxm), int(gym), int(gzm)};
  const std::size_t size = std::size_t(gxm) * gym * gzm;
  auto at = [&](int i, int j, int k) {
    return (std::size_t(k - gzs) * gym + std::size_t(j - gys)) * gxm + std::size_t(i - gxs);
  };
  std::vector<double> start(size, kSentinel);
  for (int k = zs; k < zs + zm; ++k)
    for (int j = ys; j < ys + ym; ++j)
      for (int i = xs; i < xs + xm; ++i) start[at(i, j, k)] = label(i, j, k);

  std::vector<double> petsc = start;
  Vec v;
  VecCreateSeqWithArray(PETSC_COMM_SELF, 1, PetscInt(size), petsc.data(), &v);
  ASSERT_EQ(DMLocalToLocalBegin(da, v, INSERT_VALUES, v), 0);
  ASSERT_EQ(DMLocalToLocalEnd(da, v, INSERT_VALUES, v), 0);
  VecDestroy(&v);

  CellHalo halo(MPI_COMM_WORLD, b, cs.width, cs.box ? CellHalo::Stencil::box : CellHalo::Stencil::star);
  std::vector<double> mine = start, second = start;
  for (auto& x : second) x = x == kSentinel ? x : -x;  // a second field in the same messages
  halo.exchange({&mine, &second});

  int filled = 0, wrong = 0;
  for (int k = gzs; k < gzs + gzm; ++k)
    for (int j = gys; j < gys + gym; ++j)
      for (int i = gxs; i < gxs + gxm; ++i) {
        const std::size_t c = at(i, j, k);
        EXPECT_EQ(mine[c], petsc[c]) << "cell " << i << " " << j << " " << k;
        EXPECT_EQ(second[c], petsc[c] == kSentinel ? kSentinel : -petsc[c]);
        if (petsc[c] != kSentinel && start[c] == kSentinel) {
          ++filled;
          int g[3] = {i, j, k};
          for (int d = 0; d < 3; ++d) g[d] = (g[d] + n[d]) % n[d];
          if (petsc[c] != label(g[0], g[1], g[2])) ++wrong;
        }
      }
  EXPECT_EQ(wrong, 0);
  // One message to each other rank a round: star, one round over the six faces; box, a round per
  // direction over its two faces (so on two ranks along a periodic direction, one message there).
  long expected = 0;
  std::vector<int> peers;
  for (int d = 0; d < 3; ++d) {
    if (cs.box) peers.clear();
    for (int side : {-1, 1}) {
      std::array<int, 3> c = b.coords;
      c[d] += side;
      if (c[d] < 0 || c[d] >= b.procs[d]) {
        if (!cs.periodic[d]) continue;
        c[d] = (c[d] + b.procs[d]) % b.procs[d];
      }
      const int r = c[0] + b.procs[0] * (c[1] + b.procs[1] * c[2]);
      if (r != rank && std::find(peers.begin(), peers.end(), r) == peers.end()) peers.push_back(r), ++expected;
    }
  }
  EXPECT_EQ(halo.traffic().messages, expected);
  int total = filled;
  MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  int size_world;
  MPI_Comm_size(MPI_COMM_WORLD, &size_world);
  const bool any_periodic = cs.periodic[0] || cs.periodic[1] || cs.periodic[2];
  if (size_world > 1 || any_periodic) {
    EXPECT_GT(total, 0);  // the comparison compared something
  }
  EXPECT_EQ(halo.active(), size_world > 1 || any_periodic);
  DMDestroy(&da);
}

}  // namespace

TEST(CellHalo, SameGhostsAsTheDmdaWithWalls) {
  check_case({{false, false, false}, true, 2});
  check_case({{false, false, false}, false, 1});
}

TEST(CellHalo, SameGhostsAsTheDmdaPeriodicAlongOneDirection) {
  for (int d = 0; d < 3; ++d) {
    std::array<bool, 3> p{false, false, false};
    p[d] = true;
    check_case({p, true, 2});
    check_case({p, false, 1});
  }
}

TEST(CellHalo, SameGhostsAsTheDmdaPeriodicEverywhere) {
  check_case({{true, true, true}, true, 2});
  check_case({{true, true, true}, false, 1});
  check_case({{true, false, true}, true, 1});
}
