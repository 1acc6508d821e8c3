// SPDX-License-Identifier: MIT
// What a user reads does not depend on the rank count: the default case run through the executable
// (as the README shows) on 1, 2 and 4 ranks writes the same quantities in summary.json, bit for bit
// (the state is bitwise by construction, src/solid/halo.hpp; reported sums are exact,
// src/core/exact_sum.hpp). The 2- and 4-rank runs must really split the work: bodies migrate and
// contacts cross rank boundaries, or the comparison would prove nothing.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "support/run_command.hpp"

namespace fs = std::filesystem;

namespace {

nlohmann::json run_default_case(int ranks) {
  const fs::path out = fs::temp_directory_path() / ("tessera_summary_ranks_" + std::to_string(ranks));
  fs::remove_all(out);
  const std::string src = TESSERA_SOURCE_DIR;
  const auto r =
      tessera::test::run_shell("mpirun --oversubscribe -n " + std::to_string(ranks) + " " + std::string(TESSERA_BIN) +
                               " run " + src + "/cases/deposition/small.yaml --quiet --set run.end_time=0.03" +
                               " --set output.snapshot_interval=0 --output " + out.string());
  EXPECT_EQ(r.code, 0) << r.output;
  std::ifstream file(out / "summary.json");
  return nlohmann::json::parse(file);
}

TEST(SummaryRanks, DefaultCaseQuantitiesAreBitwiseOn1To4Ranks) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;
  const auto one = run_default_case(1);
  const auto& q1 = one["quantities"];
  ASSERT_GT(q1.size(), 5u);
  for (const int ranks : {2, 4}) {
    const auto many = run_default_case(ranks);
    const auto& q = many["quantities"];
    for (const auto& [name, value] : q1.items()) {
      ASSERT_TRUE(q.contains(name)) << name;
      // Compared as JSON values: numbers are written with all 17 significant digits.
      EXPECT_EQ(q[name], value) << name << " on " << ranks << " ranks";
      if (value.is_number_float())
        std::printf("  %-26s %.17g (1 rank) %.17g (%d ranks)\n", name.c_str(), value.get<double>(),
                    q[name].get<double>(), ranks);
    }
    EXPECT_EQ(many["steps"], one["steps"]);
    // The work was really shared: grains changed owner while they fell, and the bed holds
    // contacts whose two grains live on different ranks (measured 2026-11-29: 42 and 82 migrations,
    // 190 and more cross-rank contacts on 2 and 4 ranks).
    EXPECT_GT(many["migrations"].get<long>(), 20) << ranks << " ranks";
    EXPECT_GT(many["cross_rank_contacts_checked"].get<long>(), 50) << ranks << " ranks";
  }
  EXPECT_EQ(one["migrations"].get<long>(), 0);
  EXPECT_EQ(one["cross_rank_contacts_checked"].get<long>(), 0);
}

}  // namespace
