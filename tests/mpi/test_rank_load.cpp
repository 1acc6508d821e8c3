// SPDX-License-Identifier: MIT
// The scaling model's per-rank counts (solid/rank_load.hpp), computed on one process, against what
// the ranks of a real DEM set-up hold: owned bodies, ghosts (x, y, z sweeps with forwarding) and
// listed pairs (a pair across a cut on both sides), at uneven cuts on 2 and 4 ranks.
#include <gtest/gtest.h>
#include <mpi.h>

#include <random>
#include <vector>

#include "core/config.hpp"
#include "core/decomposition.hpp"
#include "solid/dem_solver.hpp"
#include "solid/rank_load.hpp"

namespace tessera {
namespace {

constexpr const char* kSolid = R"(
solid:
  neighbor_skin: 0.4 mm
  materials: {sand: {density: 2500}}
  contact:
    law: hooke
    pairs:
      - {materials: [sand, sand], normal_stiffness: 1e4, tangential_stiffness: 2.857e3, restitution: 0.5, friction: 0.5}
)";

TEST(RankLoad, CountsWhatEachRankHolds) {
  int size = 1, rank = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  // A jittered lattice of spheres (radius 0.5 mm +- 10 %, spacing 1.05 mm) filling the lower part of
  // a 12 x 10 x 12 mm box: some touch, some are listed only through the skin.
  const Vec3 lo{0, 0, 0}, hi{12e-3, 10e-3, 12e-3};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> x;
  std::vector<double> radius;
  for (int k = 0; k < 7; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 11; ++i) {
        x.push_back({(i + 0.6) * 1.05e-3 + 0.05e-3 * u(rng), (j + 0.6) * 1.05e-3 + 0.05e-3 * u(rng),
                     (k + 0.6) * 1.05e-3 + 0.05e-3 * u(rng)});
        radius.push_back(0.5e-3 * (1 + 0.1 * u(rng)));
      }
  const Config c = Config::parse(kSolid);
  const ConfigNode solid = c.root().section("solid");
  // Grids for the rank count, with uneven cuts (the model must follow the cuts, not the slabs).
  struct Grid {
    std::array<int, 3> dims;
    CutPlanes cuts;
  };
  std::vector<Grid> grids;
  if (size == 2) grids = {{{2, 1, 1}, {{{4.3e-3}, {}, {}}}}, {{1, 1, 2}, {{{}, {}, {3.9e-3}}}}};
  if (size == 4)
    grids = {{{2, 2, 1}, {{{5.1e-3}, {3.7e-3}, {}}}}, {{2, 1, 2}, {{{6.6e-3}, {}, {2.8e-3}}}},
             {{1, 4, 1}, {{{}, {2.5e-3, 4.9e-3, 7.1e-3}, {}}}}};
  ASSERT_FALSE(grids.empty()) << "run under mpirun -n 2 or 4";
  for (const Grid& g : grids) {
    const Decomposition d(MPI_COMM_WORLD, lo, hi, g.dims, g.cuts);
    DemSettings st = DemSettings::from_config(solid);
    DemSolver dem(d, ContactModel(solid), Walls(), st);
    for (std::size_t b = 0; b < x.size(); ++b) dem.add_sphere(static_cast<std::int64_t>(b), 0, radius[b], x[b], {});
    dem.setup();
    const RankLoad load = dem_rank_load(x, radius, lo, hi, g.dims, g.cuts, 0.4e-3);
    // The grid cell this rank holds (RankLoad's order: x fastest; MPI's Cartesian ranks run z fastest).
    const auto me = static_cast<std::size_t>(d.coords()[0] + g.dims[0] * (d.coords()[1] + g.dims[1] * d.coords()[2]));
    const auto& p = dem.particles();
    EXPECT_EQ(static_cast<double>(p.owned), load.bodies[me]) << "rank " << rank;
    EXPECT_EQ(static_cast<double>(p.ghosts), load.ghosts[me]) << "rank " << rank;
    EXPECT_EQ(static_cast<double>(dem.pair_count()), load.pairs[me]) << "rank " << rank;
    // Not a vacuous comparison: every rank holds bodies, ghosts and pairs across its cut.
    EXPECT_GT(load.bodies[me], 50);
    EXPECT_GT(load.ghosts[me], 10);
    double recv = 0;
    for (const double n : load.recv[me]) recv += n;
    EXPECT_EQ(recv, load.ghosts[me]);
    double pairs = 0;
    for (const double n : load.pairs) pairs += n;
    EXPECT_GT(pairs, load.total_pairs);  // pairs across the cuts, counted on both sides
  }
}

}  // namespace
}  // namespace tessera
