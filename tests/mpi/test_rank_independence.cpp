// SPDX-License-Identifier: MIT
// Results do not depend on the rank count or the process grid: the same violent deposition on
// 1, 2 and 4 ranks, split along x, z and in two directions, ends in bitwise identical states
// (positions, velocities, angular velocities, orientations, forces, wall histories).
// Why bitwise: each contact is evaluated in canonical orientation (lower id first) and each body
// sums its contacts in partner-id order on every decomposition (see src/solid/halo.hpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "mpi/deposition_case.hpp"
#include "support/scene_runs.hpp"

namespace tessera::test {
namespace {

TEST(RankIndependence, ViolentDepositionIsBitwiseIdenticalOn1To4Ranks) {
  const int size = world_size(), rank = world_rank();
  ASSERT_EQ(size, 4) << "run under mpirun -n 4";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_rank_independence").string();
  const std::vector<std::string> steps{"run.max_steps=3000"};
  const BodyStates reference =
      run_scene_on(1, kViolentDeposition, {"run.max_steps=3000", "domain.process_grid=[1,1,1]"}, dir + "/1");
  struct Grid {
    int ranks;
    const char* grid;
  };
  for (const Grid g :
       {Grid{2, "[2,1,1]"}, Grid{2, "[1,1,2]"}, Grid{4, "[2,2,1]"}, Grid{4, "[1,1,4]"}, Grid{4, "[4,1,1]"}}) {
    const BodyStates got =
        run_scene_on(g.ranks, kViolentDeposition, {"run.max_steps=3000", std::string("domain.process_grid=") + g.grid},
                     dir + "/" + std::to_string(g.ranks) + g.grid);
    if (rank == 0) {
      EXPECT_EQ(got.size(), 1088u);
      EXPECT_EQ(count_differences(reference, got, g.grid), 0) << g.ranks << " ranks, grid " << g.grid;
      // The run must have moved: bodies far from their lattice start.
      EXPECT_LT(got.begin()->second[8], 0.3e-3 + 0.35e-3 + 0.05e-3);
    }
  }
}

TEST(RankIndependence, ShapedGrainsAreBitwiseIdenticalOn1To4Ranks) {
  // Element keys (body order * stride + sphere index) give the same canonical pair order on every
  // decomposition; element forces are summed into bodies in key order.
  const int size = world_size(), rank = world_rank();
  ASSERT_EQ(size, 4) << "run under mpirun -n 4";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_rank_independence_shaped").string();
  const BodyStates reference =
      run_scene_on(1, kViolentShapedDeposition, {"run.max_steps=5000", "domain.process_grid=[1,1,1]"}, dir + "/1");
  for (const char* grid : {"[2,1,1]", "[1,1,2]", "[2,2,1]", "[4,1,1]"}) {
    const int ranks = std::string(grid) == "[2,2,1]" || std::string(grid) == "[4,1,1]" ? 4 : 2;
    const BodyStates got = run_scene_on(ranks, kViolentShapedDeposition,
                                        {"run.max_steps=5000", std::string("domain.process_grid=") + grid},
                                        dir + "/" + std::to_string(ranks) + grid);
    if (rank == 0) {
      EXPECT_EQ(got.size(), 128u);
      EXPECT_EQ(count_differences(reference, got, grid), 0) << ranks << " ranks, grid " << grid;
      // It moved: grain 1 (bottom corner, centre 0.725 mm up at the start) fell onto the floor.
      EXPECT_LT(got.begin()->second[8], 0.6e-3);
    }
  }
}

TEST(RankIndependence, MeshWallsWithAPivotAreBitwiseIdenticalOn1To4Ranks) {
  // The paddle's load is summed over all contacts in key order on every rank.
  const int size = world_size(), rank = world_rank();
  ASSERT_EQ(size, 4) << "run under mpirun -n 4";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_rank_independence_mesh").string();
  const std::string text = mesh_case();
  const BodyStates reference = run_scene_on(1, text, {"run.max_steps=2500", "domain.process_grid=[1,1,1]"}, dir + "/1");
  for (const char* grid : {"[2,1,1]", "[1,1,2]", "[2,2,1]"}) {
    const int ranks = std::string(grid) == "[2,2,1]" ? 4 : 2;
    const BodyStates got = run_scene_on(ranks, text, {"run.max_steps=2500", std::string("domain.process_grid=") + grid},
                                        dir + "/" + std::to_string(ranks) + grid);
    if (rank == 0) {
      EXPECT_EQ(got.size(), reference.size());
      EXPECT_EQ(count_differences(reference, got, grid), 0) << ranks << " ranks, grid " << grid;
    }
  }
}

}  // namespace
}  // namespace tessera::test
