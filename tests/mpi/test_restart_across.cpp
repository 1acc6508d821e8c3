// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <filesystem>

#include "mpi/deposition_case.hpp"
#include "support/scene_runs.hpp"

namespace tessera::test {
namespace {

// Checkpoints do not depend on the rank count: a run checkpointed on N ranks continues on 1 rank to
// the same bits as a straight run (results being rank-count independent, see test_rank_independence).
TEST(Restart, ContinuesOnAnotherRankCount) {
  const int size = world_size(), rank = world_rank();
  ASSERT_GT(size, 1) << "run under mpirun -n 2 or more";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_restart_across").string();
  const BodyStates straight = run_scene_on(1, kViolentDeposition, {"run.max_steps=1600"}, dir + "/straight");
  run_scene_on(size, kViolentDeposition, {"run.max_steps=700"}, dir + "/first");
  const BodyStates resumed =
      run_scene_on(1, kViolentDeposition, {"run.max_steps=1600"}, dir + "/second", dir + "/first/checkpoint.h5");
  if (rank == 0) {
    EXPECT_EQ(straight.size(), 1088u);
    EXPECT_EQ(count_differences(straight, resumed, "restart on 1 rank"), 0);
  }
}

// The same for shaped grains: per-sphere pair and wall histories are in the checkpoint by key.
TEST(Restart, ShapedGrainsContinueOnAnotherRankCount) {
  const int size = world_size(), rank = world_rank();
  ASSERT_GT(size, 1) << "run under mpirun -n 2 or more";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_restart_across_shaped").string();
  const BodyStates straight = run_scene_on(1, kViolentShapedDeposition, {"run.max_steps=2400"}, dir + "/straight");
  run_scene_on(size, kViolentShapedDeposition, {"run.max_steps=1500"}, dir + "/first");
  const BodyStates resumed =
      run_scene_on(1, kViolentShapedDeposition, {"run.max_steps=2400"}, dir + "/second", dir + "/first/checkpoint.h5");
  if (rank == 0) {
    EXPECT_GT(straight.size(), 0u);
    EXPECT_EQ(count_differences(straight, resumed, "shaped restart on 1 rank"), 0);
  }
}

// Mesh walls: the paddle's angle and speed and the mesh contacts' springs are in the checkpoint.
TEST(Restart, MeshWallsContinueOnAnotherRankCount) {
  const int size = world_size(), rank = world_rank();
  ASSERT_GT(size, 1) << "run under mpirun -n 2 or more";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_restart_across_mesh").string();
  const std::string text = mesh_case();
  const BodyStates straight = run_scene_on(1, text, {"run.max_steps=2500"}, dir + "/straight");
  run_scene_on(size, text, {"run.max_steps=1700"}, dir + "/first");
  const BodyStates resumed =
      run_scene_on(1, text, {"run.max_steps=2500"}, dir + "/second", dir + "/first/checkpoint.h5");
  if (rank == 0) {
    EXPECT_GT(straight.size(), 0u);
    EXPECT_EQ(count_differences(straight, resumed, "mesh restart on 1 rank"), 0);
  }
}

}  // namespace
}  // namespace tessera::test
