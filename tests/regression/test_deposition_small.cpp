// SPDX-License-Identifier: MIT
// Scene-level regression: the default case (small deposition, 2 ranks) against
// deposition_small.reference.json, quantity by quantity, with the tolerances written there (from the
// seed-to-seed spread of the settled bed's statistics). The file says how to regenerate it.
#include <gtest/gtest.h>
#include <mpi.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "support/run_command.hpp"

namespace fs = std::filesystem;

namespace {

TEST(DepositionSmall, QuantitiesMatchReference) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;
  const fs::path out = fs::temp_directory_path() / "tessera_regression_deposition_small";
  fs::remove_all(out);
  const std::string src = TESSERA_SOURCE_DIR;
  const auto r = tessera::test::run_shell("mpirun --oversubscribe -n 2 " + std::string(TESSERA_BIN) + " run " + src +
                                          "/cases/deposition/small.yaml --quiet --set output.snapshot_interval=0" +
                                          " --output " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream ref_file(src + "/tests/regression/deposition_small.reference.json");
  std::ifstream got_file(out / "summary.json");
  const auto ref = nlohmann::json::parse(ref_file);
  const auto got = nlohmann::json::parse(got_file)["quantities"];
  EXPECT_TRUE(got["settled"].get<bool>());
  for (const auto& [name, spec] : ref["quantities"].items()) {
    const double value = got.at(name).get<double>();
    std::printf("  %-24s %.6g (reference %.6g +- %.3g)\n", name.c_str(), value, spec["value"].get<double>(),
                spec["tolerance"].get<double>());
    EXPECT_NEAR(value, spec["value"].get<double>(), spec["tolerance"].get<double>()) << name;
  }
}

}  // namespace
