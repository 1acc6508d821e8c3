// SPDX-License-Identifier: MIT
// Scene-level regression: the default case (small deposition, 2 ranks) against
// deposition_small.reference.json, quantity by quantity, with the tolerances written there (from the
// seed-to-seed spread of the settled bed's statistics). The file says how to regenerate it. The
// quantities are also checked against published bounds that do not come from this code.
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
  // Independent of the code's own earlier output: a settled bed of frictional monodisperse spheres
  // packs between random loose packing at high friction, 0.555 (Onoda & Liniger, PRL 64, 2727,
  // 1990), and random close packing, 0.64 (Scott & Kilgour, J. Phys. D 2, 863, 1969); its mean
  // coordination number lies between the isostatic limits of frictional (d + 1 = 4) and
  // frictionless (2d = 6) spheres (Silbert et al., PRE 65, 031304, 2002); a floor carries at most
  // the bed's weight, less with wall friction (Janssen), so the ratio is in (0.5, 1] (2 % for the
  // remaining motion at the settle threshold).
  const double phi = got["packing_fraction"].get<double>(), z = got["coordination_number"].get<double>();
  EXPECT_GT(phi, 0.555);
  EXPECT_LT(phi, 0.64);
  EXPECT_GT(z, 4.0);
  EXPECT_LT(z, 6.0);
  EXPECT_GT(got["floor_force_over_weight"].get<double>(), 0.5);
  EXPECT_LT(got["floor_force_over_weight"].get<double>(), 1.02);
  for (const auto& [name, spec] : ref["quantities"].items()) {
    const double value = got.at(name).get<double>();
    std::printf("  %-24s %.6g (reference %.6g +- %.3g)\n", name.c_str(), value, spec["value"].get<double>(),
                spec["tolerance"].get<double>());
    EXPECT_NEAR(value, spec["value"].get<double>(), spec["tolerance"].get<double>()) << name;
  }
}

}  // namespace
