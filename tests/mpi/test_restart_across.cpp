// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "mpi/deposition_case.hpp"
#include "support/scene_runs.hpp"

namespace tessera::test {
namespace {

// Checkpoints do not depend on the rank count: a run checkpointed on N ranks continues on 1 rank to
// the same bits as a straight 1-rank run (results being rank-count independent, see
// test_rank_independence).
void expect_continuation_on_one_rank(const std::string& text, long total, long first, const std::string& tag) {
  const int size = world_size(), rank = world_rank();
  ASSERT_GT(size, 1) << "run under mpirun -n 2 or more";
  const std::string dir = (std::filesystem::temp_directory_path() / ("tessera_restart_across" + tag)).string();
  const std::string end = "run.max_steps=" + std::to_string(total);
  const BodyStates straight = run_scene_on(1, text, {end}, dir + "/straight");
  run_scene_on(size, text, {"run.max_steps=" + std::to_string(first)}, dir + "/first");
  const BodyStates resumed = run_scene_on(1, text, {end}, dir + "/second", dir + "/first/checkpoint.h5");
  if (rank == 0) {
    EXPECT_GT(straight.size(), 0u);
    EXPECT_EQ(count_differences(straight, resumed, ("restart on 1 rank" + tag).c_str()), 0);
  }
}

TEST(Restart, ContinuesOnAnotherRankCount) { expect_continuation_on_one_rank(kViolentDeposition, 1600, 700, ""); }

// Shaped grains: per-sphere pair and wall springs are in the checkpoint by key.
TEST(Restart, ShapedGrainsContinueOnAnotherRankCount) {
  expect_continuation_on_one_rank(kViolentShapedDeposition, 2400, 1500, "_shaped");
}

// Mesh walls: the paddle's angle and speed and the mesh contacts' springs are in the checkpoint.
TEST(Restart, MeshWallsContinueOnAnotherRankCount) {
  expect_continuation_on_one_rank(mesh_case(), 2500, 1700, "_mesh");
}

}  // namespace
}  // namespace tessera::test
