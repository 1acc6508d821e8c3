// SPDX-License-Identifier: MIT
// Restart: running N + M steps equals running N steps, checkpointing, and restarting for M more,
// bitwise, at the same rank count (contact histories, wall histories, forces and the clock are in
// the checkpoint).
#include <gtest/gtest.h>

#include <filesystem>

#include "mpi/deposition_case.hpp"
#include "support/scene_runs.hpp"

namespace tessera::test {
namespace {

TEST(Restart, ContinuationIsBitwiseIdentical) {
  const int size = world_size(), rank = world_rank();
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("tessera_restart_np" + std::to_string(size))).string();
  const BodyStates straight = run_scene_on(size, kViolentDeposition, {"run.max_steps=2000"}, dir + "/straight");
  run_scene_on(size, kViolentDeposition, {"run.max_steps=1100"}, dir + "/first");
  const BodyStates resumed =
      run_scene_on(size, kViolentDeposition, {"run.max_steps=2000"}, dir + "/second", dir + "/first/checkpoint.h5");
  if (rank == 0) {
    EXPECT_EQ(straight.size(), 1088u);
    EXPECT_EQ(count_differences(straight, resumed, "restart"), 0);
  }
}

TEST(Restart, CheckpointIsReplacedAtomically) {
  // The checkpoint is written under a temporary name and renamed: no .tmp is left behind.
  const int size = world_size(), rank = world_rank();
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("tessera_ckpt_np" + std::to_string(size))).string();
  run_scene_on(size, kViolentDeposition, {"run.max_steps=200", "output.checkpoint_interval=1e-5"}, dir);
  if (rank == 0) {
    EXPECT_TRUE(std::filesystem::exists(dir + "/checkpoint.h5"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/checkpoint.h5.tmp"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/summary.json"));
  }
}

}  // namespace
}  // namespace tessera::test
