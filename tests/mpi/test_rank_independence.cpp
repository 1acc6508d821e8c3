// SPDX-License-Identifier: MIT
// Results do not depend on the rank count or the process grid: the same violent deposition on
// 1, 2 and 4 ranks, split along x, z and in two directions, in equal slabs or at uneven cut planes
// (domain.cuts), ends in bitwise identical states
// (positions, velocities, angular velocities, orientations, forces, wall histories).
// Each multi-rank run must have split the work (bodies migrated, contacts crossed rank boundaries)
// and the bodies must have moved, or the comparison would prove nothing.
// Why bitwise: each contact is evaluated in canonical orientation (lower id first) and each body
// sums its contacts in partner-id order on every decomposition (see src/solid/halo.hpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "mpi/deposition_case.hpp"
#include "support/scene_runs.hpp"

namespace tessera::test {
namespace {

// What makes a comparison meaningful, read from the run's summary.json (rank 0): on more than one
// rank, bodies changed owner; the bodies moved (the bed is lower than the 12 mm lattice they started
// in, when a bound is given). Returns the touching pairs across rank boundaries summed over the
// checks: a cut through free-falling grains has few, so each test asserts them over its grids.
long expect_split_and_moved(const std::string& dir, int ranks, double bed_height_below = 0) {
  std::ifstream file(dir + "/summary.json");
  const auto s = nlohmann::json::parse(file);
  EXPECT_EQ(s["migrations"].get<long>() > 0, ranks > 1) << dir;
  if (ranks > 1) {
    EXPECT_GE(s["migrations"].get<long>(), 10) << dir;
  }
  if (bed_height_below > 0) {
    EXPECT_LT(s["quantities"]["bed_height"].get<double>(), bed_height_below) << dir;
  }
  return s["cross_rank_contacts_checked"].get<long>();
}

TEST(RankIndependence, ViolentDepositionIsBitwiseIdenticalOn1To4Ranks) {
  const int size = world_size(), rank = world_rank();
  ASSERT_EQ(size, 4) << "run under mpirun -n 4";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_rank_independence").string();
  const std::vector<std::string> steps{"run.max_steps=3000", "run.check_interval=5e-5"};
  const BodyStates reference =
      run_scene_on(1, kViolentDeposition,
                   {"run.max_steps=3000", "run.check_interval=5e-5", "domain.process_grid=[1,1,1]"}, dir + "/1");
  struct Grid {
    int ranks;
    const char* grid;
    const char* cuts = "";  // uneven cut planes (domain.cuts.x, and y at 2.2 mm), or equal slabs
  };
  long cross = 0;
  for (const Grid g : {Grid{2, "[2,1,1]"}, Grid{2, "[1,1,2]"}, Grid{4, "[2,2,1]"}, Grid{4, "[1,1,4]"},
                       Grid{4, "[4,1,1]"}, Grid{4, "[2,2,1]", "x=[3.1e-3]"}}) {
    std::vector<std::string> sets{"run.max_steps=3000", "run.check_interval=5e-5",
                                  std::string("domain.process_grid=") + g.grid};
    if (*g.cuts) {
      sets.push_back(std::string("domain.cuts.") + g.cuts);
      sets.push_back("domain.cuts.y=[2.2e-3]");
    }
    const BodyStates got = run_scene_on(g.ranks, kViolentDeposition, sets,
                                        dir + "/" + std::to_string(g.ranks) + g.grid + (*g.cuts ? "cuts" : ""));
    if (rank == 0) {
      EXPECT_EQ(got.size(), 1088u);
      EXPECT_EQ(count_differences(reference, got, g.grid), 0) << g.ranks << " ranks, grid " << g.grid;
      // The lattice filled the 12 mm box; the fallen bed is 7.5 mm high (measured).
      cross += expect_split_and_moved(dir + "/" + std::to_string(g.ranks) + g.grid + (*g.cuts ? "cuts" : ""), g.ranks, 9e-3);
    }
  }
  if (rank == 0) {
    EXPECT_GE(cross, 100);  // contacts between bodies of different ranks were evaluated
  }
}

TEST(RankIndependence, ShapedGrainsAreBitwiseIdenticalOn1To4Ranks) {
  // Element keys (body order * stride + sphere index) give the same canonical pair order on every
  // decomposition; element forces are summed into bodies in key order.
  const int size = world_size(), rank = world_rank();
  ASSERT_EQ(size, 4) << "run under mpirun -n 4";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_rank_independence_shaped").string();
  const BodyStates reference =
      run_scene_on(1, kViolentShapedDeposition,
                   {"run.max_steps=5000", "run.check_interval=5e-5", "domain.process_grid=[1,1,1]"}, dir + "/1");
  // The stale bodies' pairs listed again alone (the default, theory T5a) against whole rebuilds at
  // every skin/2: the same bits, and both ways did what they say.
  const BodyStates whole =
      run_scene_on(1, kViolentShapedDeposition,
                   {"run.max_steps=5000", "run.check_interval=5e-5", "domain.process_grid=[1,1,1]",
                    "solid.neighbor_relist=false"},
                   dir + "/1whole");
  auto lists = [](const std::string& run) {
    std::ifstream file(run + "/summary.json");
    const auto s = nlohmann::json::parse(file);
    return std::pair<long, long>{s["neighbor_list_builds"].get<long>(), s["neighbor_list_relists"].get<long>()};
  };
  if (rank == 0) {
    EXPECT_EQ(count_differences(reference, whole, "whole rebuilds"), 0);
    EXPECT_GE(lists(dir + "/1").second, 20) << "relists";
    EXPECT_EQ(lists(dir + "/1whole").second, 0);
    EXPECT_GT(lists(dir + "/1whole").first, 5 * lists(dir + "/1").first) << "builds";
  }
  long cross = 0, relists = 0;
  for (const char* grid : {"[2,1,1]", "[1,1,2]", "[2,2,1]", "[4,1,1]"}) {
    const int ranks = std::string(grid) == "[2,2,1]" || std::string(grid) == "[4,1,1]" ? 4 : 2;
    const BodyStates got =
        run_scene_on(ranks, kViolentShapedDeposition,
                     {"run.max_steps=5000", "run.check_interval=5e-5", std::string("domain.process_grid=") + grid},
                     dir + "/" + std::to_string(ranks) + grid);
    if (rank == 0) {
      EXPECT_EQ(got.size(), 128u);
      EXPECT_EQ(count_differences(reference, got, grid), 0) << ranks << " ranks, grid " << grid;
      // The lattice filled the 12 mm box; the fallen bed is 5.3 mm high (measured).
      cross += expect_split_and_moved(dir + "/" + std::to_string(ranks) + grid, ranks, 8e-3);
      relists += lists(dir + "/" + std::to_string(ranks) + grid).second;
      // T5a: a rank with a stale body makes every rank relist at that sub-step (each then waits for
      // the slowest relist, not for the others' in turn), so every rank counts the same relists.
      std::ifstream file(dir + "/" + std::to_string(ranks) + grid + "/summary.json");
      const auto per_rank = nlohmann::json::parse(file)["per_rank"]["neighbor_list_relists"];
      ASSERT_EQ(per_rank.size(), static_cast<std::size_t>(ranks)) << grid;
      for (const auto& count : per_rank) EXPECT_EQ(count.get<long>(), per_rank[0].get<long>()) << grid;
    }
  }
  if (rank == 0) {
    EXPECT_GE(cross, 100);  // contacts between bodies of different ranks were evaluated
    EXPECT_GT(relists, 0);  // and bodies away from the cuts were relisted on their ranks
  }
}

TEST(RankIndependence, MeshWallsWithAPivotAreBitwiseIdenticalOn1To4Ranks) {
  // The paddle's load is summed over all contacts in key order on every rank.
  const int size = world_size(), rank = world_rank();
  ASSERT_EQ(size, 4) << "run under mpirun -n 4";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_rank_independence_mesh").string();
  const std::string text = mesh_case();
  const BodyStates reference = run_scene_on(
      1, text, {"run.max_steps=2500", "run.check_interval=5e-5", "domain.process_grid=[1,1,1]"}, dir + "/1");
  long cross = 0;
  for (const char* grid : {"[2,1,1]", "[1,1,2]", "[2,2,1]"}) {
    const int ranks = std::string(grid) == "[2,2,1]" ? 4 : 2;
    const BodyStates got = run_scene_on(
        ranks, text, {"run.max_steps=2500", "run.check_interval=5e-5", std::string("domain.process_grid=") + grid},
        dir + "/" + std::to_string(ranks) + grid);
    if (rank == 0) {
      EXPECT_EQ(got.size(), reference.size());
      EXPECT_EQ(count_differences(reference, got, grid), 0) << ranks << " ranks, grid " << grid;
      cross += expect_split_and_moved(dir + "/" + std::to_string(ranks) + grid, ranks);
    }
  }
  if (rank == 0) {
    EXPECT_GE(cross, 100);  // contacts between bodies of different ranks were evaluated
  }
}

// Issue 19: balance.enabled moves the cut planes every `interval` steps (threshold 1: whenever the
// ranks' work differs at all) and the bodies, their histories (pairs, walls, meshes, contact
// spheres) and the stages' lists follow; the bodies end bit for bit where one rank puts them. The
// falling beds leave the upper ranks of a stack along z idle, so the cuts must move far (several
// sub-domains: the migration repeats) and, where the slabs' smallest width (the contact reach)
// leaves room, the imbalance must fall. The shaped grains are caught mid-fall in their lowest
// 1.3 mm, one reach: four slabs along z cannot share that (the cuts stop at the smallest widths).
TEST(RankIndependence, RebalancingMovesTheCutsAndChangesNoBit) {
  const int size = world_size(), rank = world_rank();
  ASSERT_EQ(size, 4) << "run under mpirun -n 4";
  const std::string dir = (std::filesystem::temp_directory_path() / "tessera_rank_independence_balance").string();
  struct Case {
    const char* name;
    std::string text;
    long steps;
    const char* grid;
    int ranks;
    double gain;  // the largest fall of the imbalance one rebalance must reach
    const char* measure = "counts";
  };
  const std::vector<Case> cases = {{"spheres", kViolentDeposition, 3000, "[1,1,4]", 4, 0.1},
                                   {"spheres", kViolentDeposition, 3000, "[2,2,1]", 4, 0.0},
                                   {"shaped", kViolentShapedDeposition, 5000, "[1,1,4]", 4, 0.0},
                                   {"mesh", mesh_case(), 2500, "[1,1,2]", 2, 0.3},
                                   // Cuts from measured seconds: they differ from run to run, the bits do not.
                                   {"spheres", kViolentDeposition, 3000, "[1,1,4]", 4, 0.0, "time"}};
  std::map<std::string, BodyStates> reference;
  for (const Case& c : cases) {
    const std::string steps = "run.max_steps=" + std::to_string(c.steps);
    if (!reference.count(c.name))
      reference[c.name] = run_scene_on(1, c.text, {steps, "run.check_interval=5e-5", "domain.process_grid=[1,1,1]"},
                                       dir + "/" + c.name + "1");
    const std::string out = dir + "/" + c.name + c.grid + c.measure;
    const BodyStates got =
        run_scene_on(c.ranks, c.text,
                     {steps, "run.check_interval=5e-5", std::string("domain.process_grid=") + c.grid,
                      "balance.enabled=true", "balance.interval=250", "balance.threshold=1.0",
                      std::string("balance.measure=") + c.measure},
                     out);
    if (rank == 0) {
      EXPECT_EQ(got.size(), reference[c.name].size());
      EXPECT_EQ(count_differences(reference[c.name], got, c.grid), 0) << c.name << " " << c.grid;
      std::ifstream file(out + "/summary.json");
      const auto s = nlohmann::json::parse(file);
      const auto& b = s["balance"];
      double gained = 0;  // the largest fall of one rebalance
      for (const auto& e : b["events"])
        if (e.contains("after")) gained = std::max(gained, e["before"].get<double>() - e["after"].get<double>());
      std::printf("%s %s %s: %ld rebalances; first imbalance %.3f, last %.3f -> %.3f, largest fall %.3f; at the end %.3f\n",
                  c.name, c.grid, c.measure, b["rebalances"].get<long>(), b["first_imbalance"].get<double>(),
                  b["last_before"].get<double>(), b.value("last_after", 0.0), gained, s["imbalance"].get<double>());
      EXPECT_GE(b["rebalances"].get<long>(), 3) << c.name << " " << c.grid;
      EXPECT_GE(gained, c.gain) << c.name << " " << c.grid;
    }
  }
}

}  // namespace
}  // namespace tessera::test
