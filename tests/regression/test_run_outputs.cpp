// SPDX-License-Identifier: MIT
// What a run leaves behind: summary.json with its documented keys, an XDMF time series whose every
// HDF5 reference resolves to a dataset of the stated shape, and, on SIGTERM, a checkpoint, an
// "interrupted" summary and exit code 3.
#include <gtest/gtest.h>
#include <mpi.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "core/h5_file.hpp"
#include "support/run_command.hpp"

namespace fs = std::filesystem;

namespace {

using tessera::test::run_shell;

const std::string kCase = std::string(TESSERA_SOURCE_DIR) + "/cases/deposition/small.yaml";
const std::string kSmall =
    " --set 'deposition.region_max=[12 mm, 12 mm, 3 mm]' --set output.snapshot_interval=1e-3"
    " --set output.progress_interval=0.5";

bool rank0() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank == 0;
}

TEST(RunOutputs, SummaryAndXdmfSnapshotsAreComplete) {
  if (!rank0()) return;
  const fs::path out = fs::temp_directory_path() / "tessera_outputs";
  fs::remove_all(out);
  const auto r = run_shell(std::string(TESSERA_BIN) + " run " + kCase + kSmall + " --set run.max_steps=3000 --output " +
                           out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("packing_fraction"), std::string::npos) << r.output;  // quantities printed
  std::ifstream in(out / "summary.json");
  const auto s = nlohmann::json::parse(in);
  for (const char* key : {"code_version", "ranks", "process_grid", "steps", "time", "wall_seconds", "quantities",
                          "timers", "case", "status"})
    EXPECT_TRUE(s.contains(key)) << key;
  EXPECT_EQ(s["status"], "completed");
  EXPECT_EQ(s["steps"], 3000);
  for (const auto& [phase, t] : s["timers"].items()) {
    EXPECT_LE(t["min"].get<double>(), t["avg"].get<double>()) << phase;
    EXPECT_LE(t["avg"].get<double>(), t["max"].get<double>()) << phase;
  }
  EXPECT_EQ(s["case"]["deposition"]["diameter"], 6e-4);  // resolved case in SI
  EXPECT_TRUE(fs::exists(out / "case.resolved.yaml"));
  EXPECT_TRUE(fs::exists(out / "bed.data"));

  // Every DataItem of the XDMF names an existing dataset with the stated dimensions.
  std::ifstream x(out / "snapshots/particles.xmf");
  std::stringstream text;
  text << x.rdbuf();
  const std::string xmf = text.str();
  const std::regex item(R"(Dimensions="(\d+)( (\d+))?">([^:<]+):/(\w+)</DataItem>)");
  int items = 0;
  for (auto it = std::sregex_iterator(xmf.begin(), xmf.end(), item); it != std::sregex_iterator(); ++it, ++items) {
    const auto& m = *it;
    tessera::H5File f = tessera::H5File::open_read((out / "snapshots" / m[4].str()).string(), MPI_COMM_SELF);
    int cols = 0;
    const auto data = f.read_all<double>(m[5].str(), cols);
    const long rows = std::stol(m[1].str());
    const int want_cols = m[3].matched ? std::stoi(m[3].str()) : 1;
    EXPECT_EQ(cols, want_cols) << m[5];
    EXPECT_EQ(static_cast<long>(data.size()), rows * want_cols) << m[5];
  }
  EXPECT_GE(items, 7 * 2);  // at least two time steps of 7 arrays
  EXPECT_NE(xmf.find("<Time Value="), std::string::npos);
}

TEST(RunOutputs, SigtermWritesCheckpointAndStops) {
  if (!rank0()) return;
  const fs::path out = fs::temp_directory_path() / "tessera_sigterm";
  fs::remove_all(out);
  const auto r = run_shell(std::string(TESSERA_BIN) + " run " + kCase + kSmall + " --output " + out.string() +
                           " & pid=$!; sleep 3; kill -TERM $pid; wait $pid; echo exit=$?");
  EXPECT_NE(r.output.find("exit=3"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(out / "checkpoint.h5"));
  std::ifstream in(out / "summary.json");
  ASSERT_TRUE(in.good());
  EXPECT_EQ(nlohmann::json::parse(in)["status"], "interrupted");
}

TEST(RunOutputs, BlowUpStopsWithMessageAndDump) {
  if (!rank0()) return;
  const fs::path out = fs::temp_directory_path() / "tessera_blowup";
  fs::remove_all(out);
  // dt four times the contact duration: grains pass through each other.
  const auto r = run_shell(std::string(TESSERA_BIN) + " run " + kCase + kSmall + " --set solid.time_step=1e-4" +
                           " --output " + out.string());
  EXPECT_EQ(r.code, 4) << r.output;
  EXPECT_NE(r.output.find("blow-up at step"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("steps_per_contact"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(out / "failure.h5"));
}

}  // namespace
