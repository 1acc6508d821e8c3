// SPDX-License-Identifier: MIT
// The tessera executable: bad input stops before any work with one message and exit code 2, and
// leaves no output behind; `tessera balance` reports a checkpoint's imbalance on P ranks.
#include <gtest/gtest.h>
#include <mpi.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "support/run_command.hpp"

namespace {

using tessera::test::run_shell;

tessera::test::CommandResult run(const std::string& args) { return run_shell(std::string(TESSERA_BIN) + " " + args); }

TEST(Cli, BadInputStopsWithExitCode2AndWritesNothing) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "tessera_cli_bad_input";
  std::filesystem::remove_all(out);
  const std::string base = std::string(TESSERA_SOURCE_DIR) + "/cases/deposition/small.yaml --output " + out.string();
  auto r = run("run " + base + " --set deposition.diameter=-1");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("deposition.diameter"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
  r = run("run " + base + " --set solid.typo=1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("solid.typo"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
  r = run("run /nonexistent/case.yaml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("a readable YAML file"), std::string::npos) << r.output;
  r = run("info");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("fluid"), std::string::npos);
}

// The deposition's lattice of 9720 spheres fills its box up to 20.2 of 21.5 mm: on 4 ranks stacked
// along z (1x1x4) equal slabs give the top rank 4.1 mm of lattice against 5.4 (imbalance
// 5.375 / 5.056 = 1.063 up to the rows), balanced cuts a quarter of the rows each (the report's JSON).
TEST(Cli, BalanceReportsTheImbalanceOfACheckpoint) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "tessera_cli_balance";
  std::filesystem::remove_all(out);
  const std::string case_file = std::string(TESSERA_SOURCE_DIR) + "/cases/deposition/small.yaml";
  auto r = run("run " + case_file + " --output " + out.string() + " --set run.max_steps=1 --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string json = (out / "balance.json").string();
  r = run("balance " + case_file + " --bodies " + (out / "checkpoint.h5").string() + " --ranks 1,4 --json " + json +
          " --set domain.process_grid=[1,1,0]");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(json);
  const auto report = nlohmann::json::parse(in);
  EXPECT_EQ(report["count"].get<long>(), 9720);
  const auto& table = report["table"];
  ASSERT_EQ(table.size(), 2u);
  EXPECT_DOUBLE_EQ(table[0]["imbalance_equal"].get<double>(), 1.0);  // one rank holds everything
  EXPECT_DOUBLE_EQ(table[0]["imbalance_balanced"].get<double>(), 1.0);
  const auto grid = table[1]["grid"].get<std::vector<int>>();
  EXPECT_EQ(grid, (std::vector<int>{1, 1, 4}));
  EXPECT_NEAR(table[1]["imbalance_equal"].get<double>(), 1.063, 0.02) << r.output;
  EXPECT_LT(table[1]["imbalance_balanced"].get<double>(), 1.01) << r.output;
  // The scaling model's counts (solid/rank_load.hpp, checked against real ranks in test_rank_load):
  // one rank evaluates every listed pair once and holds no ghosts; four count the cut's pairs twice.
  const auto& one = table[0]["load_balanced"];
  EXPECT_GT(one["total_pairs"].get<double>(), 9720);
  EXPECT_EQ(one["pairs"][0].get<double>(), one["total_pairs"].get<double>());
  EXPECT_EQ(one["ghosts"][0].get<double>(), 0.0);
  double four = 0;
  for (const auto& n : table[1]["load_balanced"]["pairs"]) four += n.get<double>();
  EXPECT_GT(four, one["total_pairs"].get<double>());
  // The same bodies in a coupled case's accounting (FlowScene::rank_work): 10 x 10 x 43 cells of
  // 0.5 mm, each weighing balance.cell_weight, plus each body's work times coupling.substeps. Equal
  // slabs along z own the cells whose centres they hold: 11, 10, 11, 11 layers of 100 cells.
  const std::string coupled = " --set scene=coupled --set fluid.cells=[10,10,43] --set domain.process_grid=[1,1,0]";
  r = run("balance " + case_file + " --bodies " + (out / "checkpoint.h5").string() + " --ranks 1,4 --json " + json +
          coupled + " --set coupling.substeps=3");
  ASSERT_EQ(r.code, 0) << r.output;
  {
    std::ifstream cin(json);
    const auto c = nlohmann::json::parse(cin);
    EXPECT_EQ(c["cells"].get<double>(), 4300.0);
    const double one = c["table"][0]["work_per_rank_equal"][0].get<double>();
    const double bodies = one - 4300;  // 3 x (1 + listed pairs) per body
    EXPECT_EQ(bodies, 3 * table[0]["work_per_rank_equal"][0].get<double>()) << r.output;
    const auto equal = c["table"][1]["work_per_rank_equal"].get<std::vector<double>>();
    const auto dem = table[1]["work_per_rank_equal"].get<std::vector<double>>();
    const double layers[4] = {11, 10, 11, 11};
    for (int k = 0; k < 4; ++k) EXPECT_EQ(equal[k], 3 * dem[k] + 100 * layers[k]) << k;
  }
  // Cells that outweigh the bodies: the cuts share the 43 layers as 11, 11, 11, 10 (1.023).
  r = run("balance " + case_file + " --bodies " + (out / "checkpoint.h5").string() + " --ranks 4 --json " + json +
          coupled + " --set coupling.substeps=3 --set balance.cell_weight=1e6");
  ASSERT_EQ(r.code, 0) << r.output;
  {
    std::ifstream cin(json);
    const auto c = nlohmann::json::parse(cin);
    EXPECT_NEAR(c["table"][0]["imbalance_balanced"].get<double>(), 11 / 10.75, 1e-3) << r.output;
  }
  // Without the sub-steps the bodies cannot be weighed against the cells.
  r = run("balance " + case_file + " --bodies " + (out / "checkpoint.h5").string() + " --ranks 4" + coupled);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("coupling.substeps"), std::string::npos) << r.output;
  r = run("balance " + case_file + " --bodies " + (out / "checkpoint.h5").string() + " --ranks four");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--ranks"), std::string::npos) << r.output;
}

TEST(Cli, BalanceReportsABlastCasesPartitions) {
  // The blast's elements on 1, 4 and 16 ranks (no checkpoint: the mesh and the initial levels): one
  // rank holds everything; on 4 the hole's small elements make equal slabs carry 1.6 times the
  // mean, METIS's per-level partition is within the issue-19 goal of 1.05 in the macro step's sum
  // and in its sub-steps (each waits for its busiest rank). On 16 (60 elements per rank) no
  // partition reaches the goal; METIS's, the shorter of per-level and sum-only, has the shortest
  // sub-steps.
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;
  const std::string json = (std::filesystem::temp_directory_path() / "tessera_cli_blast_balance.json").string();
  const std::string case_file = std::string(TESSERA_SOURCE_DIR) + "/cases/blast/blast.yaml";
  const auto r = run("balance " + case_file + " --ranks 1,4,16 --set blast.stepping=stability --json " + json);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(json);
  const auto report = nlohmann::json::parse(in);
  const auto& table = report["table"];
  ASSERT_EQ(table.size(), 3u);
  for (const char* how : {"slabs", "balanced", "metis"}) {
    EXPECT_DOUBLE_EQ(table[0][how]["imbalance"].get<double>(), 1.0) << how;
    EXPECT_DOUBLE_EQ(table[0][how]["substep_imbalance"].get<double>(), 1.0) << how;
    EXPECT_GT(table[0][how]["substep_time"].get<double>(), 0.0) << how;  // tools/scaling.py model reads it
    EXPECT_EQ(table[0][how]["cut_bonds"].get<long>(), 0) << how;
    EXPECT_EQ(table[2][how]["work_per_rank"].size(), 16u) << how;
    EXPECT_GE(table[1][how]["level_imbalance"].size(), 2u) << how;
    EXPECT_EQ(table[1][how]["level_halo_sent"].size(), table[1][how]["level_imbalance"].size()) << how;  // scaling.py
    EXPECT_EQ(table[1][how]["halo_neighbours"].size(), 4u) << how;
  }
  EXPECT_GT(table[1]["slabs"]["imbalance"].get<double>(), 1.5) << r.output;
  EXPECT_LE(table[1]["metis"]["imbalance"].get<double>(), 1.05) << r.output;
  EXPECT_LE(table[1]["metis"]["substep_imbalance"].get<double>(), 1.05) << r.output;
  const double metis16 = table[2]["metis"]["substep_imbalance"].get<double>();
  EXPECT_LT(metis16, table[2]["balanced"]["substep_imbalance"].get<double>()) << r.output;
  EXPECT_LT(metis16, table[2]["slabs"]["substep_imbalance"].get<double>()) << r.output;
  // The per-level partition's sum is 1.17 there but its sub-steps 1.19; the sum alone gives 1.04 and
  // 2.07 (2026-11-30). The choice by the sub-steps' time takes the first; by the sum, the second.
  EXPECT_LT(metis16, 1.5) << r.output;
}

}  // namespace
