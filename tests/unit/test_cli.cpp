// SPDX-License-Identifier: MIT
// The tessera executable: bad input stops before any work with one message and exit code 2, and
// leaves no output behind.
#include <gtest/gtest.h>
#include <mpi.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

namespace {

struct Result {
  int code;
  std::string output;
};

Result run(const std::string& args) {
  // The child must not inherit this test's MPI singleton environment.
  const std::string cmd = "env -i PATH=/usr/bin:/bin OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " TESSERA_BIN
                          " " + args + " 2>&1";
  Result r{0, ""};
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), p)) r.output += buf.data();
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(Cli, BadInputStopsWithExitCode2AndWritesNothing) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "tessera_cli_bad_input";
  std::filesystem::remove_all(out);
  const std::string base = std::string(TESSERA_SOURCE_DIR) + "/cases/deposition/small.yaml --output " + out.string();
  Result r = run("run " + base + " --set deposition.diameter=-1");
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
