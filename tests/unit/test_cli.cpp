// SPDX-License-Identifier: MIT
// The tessera executable: bad input stops before any work with one message and exit code 2, and
// leaves no output behind.
#include <gtest/gtest.h>
#include <mpi.h>

#include <filesystem>
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

}  // namespace
