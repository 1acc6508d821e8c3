// SPDX-License-Identifier: MIT
// What a run leaves behind: summary.json with its documented keys, an XDMF time series whose every
// HDF5 reference resolves to a dataset of the stated shape, and, on SIGTERM, a checkpoint, an
// "interrupted" summary and exit code 3.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
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

// Every DataItem of the XDMF names an existing dataset with the stated dimensions; every time
// appears once (ParaView reads two grids at one time as an empty multiblock).
void check_xdmf(const fs::path& dir, const std::string& name, int arrays) {
  std::ifstream x(dir / name);
  std::stringstream text;
  text << x.rdbuf();
  const std::string xmf = text.str();
  const std::regex item(R"(Dimensions="(\d+)( (\d+))?">([^:<]+):/(\w+)</DataItem>)");
  int items = 0;
  for (auto it = std::sregex_iterator(xmf.begin(), xmf.end(), item); it != std::sregex_iterator(); ++it, ++items) {
    const auto& m = *it;
    tessera::H5File f = tessera::H5File::open_read((dir / m[4].str()).string(), MPI_COMM_SELF);
    int cols = 0;
    const auto data = f.read_all<double>(m[5].str(), cols);
    const long rows = std::stol(m[1].str());
    const int want_cols = m[3].matched ? std::stoi(m[3].str()) : 1;
    EXPECT_EQ(cols, want_cols) << m[5];
    EXPECT_EQ(static_cast<long>(data.size()), rows * want_cols) << m[5];
  }
  EXPECT_GE(items, arrays * 2) << name;  // at least two time steps
  const std::regex time(R"(<Time Value="([^"]+)\"/>)");
  std::set<std::string> times;
  int count = 0;
  for (auto it = std::sregex_iterator(xmf.begin(), xmf.end(), time); it != std::sregex_iterator(); ++it, ++count)
    times.insert((*it)[1].str());
  EXPECT_GE(count, 2) << name;
  EXPECT_EQ(times.size(), static_cast<std::size_t>(count)) << name << ": a time appears twice";
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

  check_xdmf(out / "snapshots", "particles.xmf", 7);
}

// fluid.energy_budget (theory F12a): series.csv gets potential_energy and the three stages' sums,
// summary.json quantities.energy_budget, the snapshots advection_energy_source (in the XDMF). The
// stages account for the whole energy: between any two rows of the series, kinetic + potential
// changes by the change of the three sums (bound 1e-9 of the energies: the rows' 10 digits).
TEST(RunOutputs, FlowEnergyBudgetInSeriesSummaryAndFields) {
  if (!rank0()) return;
  const fs::path out = fs::temp_directory_path() / "tessera_energy_budget";
  fs::remove_all(out);
  const auto r = run_shell(std::string(TESSERA_BIN) + " run " + TESSERA_SOURCE_DIR +
                           "/cases/drop_impact/pool_bench.yaml --quiet --set fluid.cells=[16,16,16] --set run.end_time=1e-3"
                           " --set fluid.energy_budget=true --set output.series_interval=1e-4"
                           " --set output.snapshot_interval=5e-4 --output " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out / "summary.json");
  const auto s = nlohmann::json::parse(in);
  ASSERT_TRUE(s["quantities"].contains("energy_budget"));
  for (const char* stage : {"advection", "viscous", "projection"})
    EXPECT_TRUE(s["quantities"]["energy_budget"].contains(stage)) << stage;
  std::ifstream csv(out / "series.csv");
  std::string line;
  std::getline(csv, line);
  std::vector<std::string> names;
  for (std::stringstream h(line); std::getline(h, line, ',');) names.push_back(line);
  auto column = [&](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    EXPECT_NE(it, names.end()) << name;
    return int(it - names.begin());
  };
  const int ke = column("kinetic_energy"), pe = column("potential_energy"), adv = column("energy_advection"),
            vis = column("energy_viscous"), pro = column("energy_projection");
  std::vector<std::vector<double>> rows;
  while (std::getline(csv, line)) {
    std::vector<double> row;
    std::stringstream l(line);
    for (std::string v; std::getline(l, v, ',');) row.push_back(std::atof(v.c_str()));
    rows.push_back(row);
  }
  ASSERT_GE(rows.size(), 5u);
  const auto& a = rows.front();
  const auto& b = rows.back();
  const double whole = (b[ke] + b[pe]) - (a[ke] + a[pe]);
  const double stages = (b[adv] + b[vis] + b[pro]) - (a[adv] + a[vis] + a[pro]);
  EXPECT_LT(b[adv] - a[adv], 0.0);  // the pool drop loses energy to the advection (docs/performance.md)
  EXPECT_LT(std::abs(whole - stages), 1e-9 * (a[ke] + std::abs(a[pe])));
  std::ifstream x(out / "fields" / "fields.xmf");
  std::stringstream text;
  text << x.rdbuf();
  EXPECT_NE(text.str().find("fields_00002.h5:/advection_energy_source"), std::string::npos) << text.str();
  EXPECT_TRUE(fs::exists(out / "fields" / "fields_00002.h5"));

  // A restart goes on with the budget (the checkpoint carries it): stopped at 0.5 ms and restarted,
  // the same sums as the run above (the flow's restart is bitwise; bound 1e-12 of each).
  const fs::path half = fs::temp_directory_path() / "tessera_energy_budget_restart";
  fs::remove_all(half);
  const std::string common = std::string(TESSERA_BIN) + " run " + TESSERA_SOURCE_DIR +
                             "/cases/drop_impact/pool_bench.yaml --quiet --set fluid.cells=[16,16,16]"
                             " --set fluid.energy_budget=true --set output.series_interval=1e-4"
                             " --set output.snapshot_interval=5e-4 --output " + half.string();
  ASSERT_EQ(run_shell(common + " --set run.end_time=5e-4").code, 0);
  const auto again = run_shell(common + " --set run.end_time=1e-3 --restart " + (half / "checkpoint.h5").string());
  ASSERT_EQ(again.code, 0) << again.output;
  std::ifstream in2(half / "summary.json");
  const auto s2 = nlohmann::json::parse(in2);
  for (const char* stage : {"advection", "viscous", "projection"}) {
    const double whole_run = s["quantities"]["energy_budget"][stage], restarted = s2["quantities"]["energy_budget"][stage];
    EXPECT_NEAR(restarted, whole_run, 1e-12 * std::abs(whole_run)) << stage;
  }
}

// case.resolved.yaml is the case as run: run again, it must resolve to the same text and give the
// same answer (its defaults once included sentinels, time_step 0 and density 0, that the reader
// refused, and lists of sections came out as mappings). The shaped-grain bed has lists of sections
// (shapes, contact pairs, walls) and every such default.
TEST(RunOutputs, ResolvedCaseRunsAgainToTheSameAnswer) {
  if (!rank0()) return;
  const fs::path a = fs::temp_directory_path() / "tessera_resolved_a", b = fs::temp_directory_path() / "tessera_resolved_b";
  fs::remove_all(a), fs::remove_all(b);
  const auto first = run_shell(std::string(TESSERA_BIN) + " run " + std::string(TESSERA_SOURCE_DIR) +
                               "/cases/grain_bed/small.yaml --quiet --set deposition.max_grains=20"
                               " --set run.max_steps=200 --output " + a.string());
  ASSERT_EQ(first.code, 0) << first.output;
  const auto again = run_shell(std::string(TESSERA_BIN) + " run " + (a / "case.resolved.yaml").string() +
                               " --quiet --output " + b.string());
  ASSERT_EQ(again.code, 0) << again.output;
  auto text = [](const fs::path& f) {
    std::ifstream in(f);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  EXPECT_EQ(text(a / "case.resolved.yaml"), text(b / "case.resolved.yaml"));
  std::ifstream ia(a / "summary.json"), ib(b / "summary.json");
  const auto sa = nlohmann::json::parse(ia), sb = nlohmann::json::parse(ib);
  EXPECT_EQ(sa["steps"], sb["steps"]);
  EXPECT_EQ(sa["quantities"].dump(), sb["quantities"].dump());
}

TEST(RunOutputs, ResolvedCaseFindsTheCaseFilesRelativePaths) {
  // The blast case's mesh (block.msh) is relative to cases/blast/; its resolved case, in the output
  // directory, records that directory as case_directory and runs again from there.
  if (!rank0()) return;
  const fs::path a = fs::temp_directory_path() / "tessera_relative_a", b = fs::temp_directory_path() / "tessera_relative_b";
  fs::remove_all(a), fs::remove_all(b);
  const std::string quick = " --quiet --set output.snapshot_interval=0 --set run.end_time=2e-7";
  const auto first = run_shell(std::string(TESSERA_BIN) + " run " + std::string(TESSERA_SOURCE_DIR) +
                               "/cases/blast/blast.yaml" + quick + " --output " + a.string());
  ASSERT_EQ(first.code, 0) << first.output;
  const auto again = run_shell(std::string(TESSERA_BIN) + " run " + (a / "case.resolved.yaml").string() +
                               " --quiet --output " + b.string());
  ASSERT_EQ(again.code, 0) << again.output;
  std::ifstream ia(a / "summary.json"), ib(b / "summary.json");
  const auto sa = nlohmann::json::parse(ia), sb = nlohmann::json::parse(ib);
  EXPECT_EQ(sa["quantities"].dump(), sb["quantities"].dump());
}

TEST(RunOutputs, ShapedGrainsWriteTheirSurfaces) {
  // 40 seed grains, ending on a snapshot time (0.5 ms = 680 steps of 7.35e-7 s, rounded up).
  if (!rank0()) return;
  const fs::path out = fs::temp_directory_path() / "tessera_outputs_shaped";
  fs::remove_all(out);
  const auto r = run_shell(std::string(TESSERA_BIN) + " run " + std::string(TESSERA_SOURCE_DIR) +
                           "/cases/grain_bed/small.yaml --quiet --set deposition.max_grains=40"
                           " --set run.end_time=0.5e-3 --set output.snapshot_interval=0.25e-3 --output " +
                           out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  check_xdmf(out / "snapshots", "particles.xmf", 7);
  check_xdmf(out / "snapshots", "grains.xmf", 4);
  std::ifstream in(out / "summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["quantities"]["bodies"], 40);
  EXPECT_EQ(s["quantities"]["grain_contact_spheres"], 75);
  EXPECT_NEAR(s["quantities"]["grain_mass"].get<double>(), 4.1766e-7, 1e-10);  // tetrahedral volume x 2650
  // bed.data: 40 x 75 contact spheres with molecule ids (LAMMPS rigid/small).
  std::ifstream data(out / "bed.data");
  std::string line;
  bool molecules = false;
  long atoms = 0, molecule_rows = 0;
  while (std::getline(data, line)) {
    if (line.find(" atoms") != std::string::npos && atoms == 0) atoms = std::stol(line);
    if (line == "Molecules")
      molecules = true;
    else if (molecules && !line.empty())
      ++molecule_rows;
  }
  EXPECT_EQ(atoms, 3000);
  EXPECT_EQ(molecule_rows, 3000);
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
