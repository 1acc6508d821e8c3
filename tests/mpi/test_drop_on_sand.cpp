// SPDX-License-Identifier: MIT
// A short piece of the drop-impact scene from its shipped cases (cases/drop_on_sand: bed_small.yaml,
// small.yaml), shrunk to run in seconds: a one-layer lattice bed of the small case's grains (169 in
// the bottom layer, 31 more above; not settled) under a coarse grid, a few flow steps of the 9 m/s drop.
//  - the bed's porosity below a plane between the two layers against the grain count times the
//    tetrahedral volume the bed's own summary reports (a different computation: tet mass
//    properties against clipping), to round-off;
//  - the drop: placed centre_above_bed above the bed's top, its liquid volume that of the
//    equivalent sphere (to the initial sampling's error), its mass and momentum reported;
//  - the crater quantities and files exist; 1 and 2 ranks agree (the bed bit for bit, the crater
//    after the flow steps to the pressure solver's tolerance); a restart continues crater.csv and
//    ends bit for bit where the straight run ends;
//  - a drop that would start in the bed is refused at set-up, naming the key; so is a bed with a body
//    outside the box, naming the body;
//  - the bed's boosted fall (theory D0): before any grain touches, the mean speed is 4 g t; the run
//    ends after_landing after the top grain's landing.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "core/errors.hpp"
#include "support/scene_runs.hpp"

using namespace tessera;
using tessera::test::world_rank;
using tessera::test::world_size;
namespace fs = std::filesystem;

namespace {

const std::string kDir = "drop_on_sand_out";
constexpr double kPlane = 2.59e-3;  // between the lattice's first layer (tops <= 2.585 mm) and the second

std::string cases(const char* name) {
  return test::file_text(std::string(TESSERA_SOURCE_DIR) + "/cases/drop_on_sand/" + name);
}

// The bed: the lattice as laid (one step of the deposition), 200 grains.
const nlohmann::json& bed() {
  static const nlohmann::json s = test::run_case_on(
      world_size(), cases("bed_small.yaml"),
      {"deposition.max_grains=200", "run.max_steps=1", "output.snapshot_interval=0", "output.progress_interval=1000"},
      kDir + "/bed");
  return s;
}

nlohmann::json drop_run(int ranks, std::vector<std::string> sets, const std::string& dir,
                        std::optional<std::string> restart = {}) {
  bed();
  sets.insert(sets.end(), {"bodies.file=" + fs::absolute(kDir + "/bed/checkpoint.h5").string(),
                           "fluid.cells=[32, 32, 24]", "crater.porosity_height=2.59 mm",
                           "output.snapshot_interval=0.05 ms", "output.progress_interval=1000"});
  return test::run_case_on(ranks, cases("small.yaml"), sets, dir, restart);
}

std::vector<double> row_times(const std::string& path) {
  std::ifstream f(path);
  std::vector<double> t;
  std::string l;
  std::getline(f, l);  // header
  while (std::getline(f, l)) t.push_back(std::stod(l.substr(0, l.find(','))));
  return t;
}

}  // namespace

TEST(DropOnSand, PlacesTheDropAndMeasuresTheBed) {
  const auto s = drop_run(world_size(), {"run.max_steps=6"}, kDir + "/two");
  if (world_rank() != 0) return;
  const auto& q = s["quantities"];
  const auto& b = bed()["quantities"];
  ASSERT_EQ(b["bodies"].get<long>(), 200);
  // 169 grains (13 x 13) lie wholly below the plane, 31 wholly above it.
  const double solid = 169 * b["grain_volume"].get<double>();
  const double expected = 1 - solid / (33.8e-3 * 33.8e-3 * kPlane);
  EXPECT_NEAR(q["bed_porosity_start"].get<double>(), expected, 1e-12);
  std::printf("  porosity below %.2f mm %.6f (expected %.6f), bed top %.4f mm\n", kPlane * 1e3,
              q["bed_porosity_start"].get<double>(), expected, q["bed_top"].get<double>() * 1e3);
  // The bed's top: the highest node of the first-layer grains, centres at 1.295 +- 0.02 mm, reaching
  // at most their bounding radius (1.27 mm) and at least their short semi-axis (0.52 mm) above it.
  EXPECT_GT(q["bed_top"].get<double>(), 1.295e-3 - 0.02e-3 + 0.52e-3 * 0.99);
  EXPECT_LT(q["bed_top"].get<double>(), 1.295e-3 + 0.02e-3 + 1.27e-3);
  // The drop: the seed's mass and momentum; its liquid volume (sampled at 8^3 points per cell).
  const double D = 5.537e-3, m = 1000 * std::numbers::pi / 6 * D * D * D;
  EXPECT_NEAR(q["drop_mass"].get<double>(), m, 1e-12 * m);
  EXPECT_NEAR(q["drop_momentum"].get<double>(), 9.0 * m, 1e-12 * m);
  EXPECT_NEAR(q["liquid_volume"].get<double>(), m / 1000, 0.01 * m / 1000);
  EXPECT_LT(std::abs(q["liquid_volume_drift"].get<double>()), 1e-12);
  for (const char* k : {"crater_volume", "crater_volume_start", "crater_depth", "crater_rim_radius",
                        "crater_section_volume", "bed_porosity"})
    EXPECT_TRUE(q.contains(k)) << k;
  // Six flow steps move no grain by a grain's length.
  EXPECT_EQ(q["displaced_grains"].get<long>(), 0);
  EXPECT_NEAR(q["ejection_distance"].get<double>(), 2 * 1.27e-3, 0.05e-3);  // the grain's length
  for (const char* f : {"crater.csv", "crater_rings.csv", "crater_surface.csv"})
    EXPECT_TRUE(fs::exists(kDir + "/two/" + f)) << f;
  // The bed's crater measure before the drop is crater.csv's first row (t = 0), whatever its sign.
  std::ifstream csv(kDir + "/two/crater.csv");
  std::string header, first;
  std::getline(csv, header);
  std::getline(csv, first);
  const double v0 = std::stod(first.substr(first.find(',') + 1));
  EXPECT_EQ(std::stod(first.substr(0, first.find(','))), 0.0);
  EXPECT_NEAR(q["crater_volume_start"].get<double>(), v0, 1e-9 * std::abs(v0) + 1e-20);
}

TEST(DropOnSand, SameCraterOnOneAndTwoRanks) {
  const auto one = drop_run(1, {"run.max_steps=6"}, kDir + "/ranks1");
  const auto two = drop_run(world_size(), {"run.max_steps=6"}, kDir + "/ranks2");
  if (world_rank() != 0) return;
  const auto &a = one["quantities"], &b = two["quantities"];
  // The bed before the drop: bit for bit.
  EXPECT_EQ(a["crater_volume_start"].get<double>(), b["crater_volume_start"].get<double>());
  EXPECT_EQ(a["bed_top"].get<double>(), b["bed_top"].get<double>());
  EXPECT_EQ(a["bed_porosity_start"].get<double>(), b["bed_porosity_start"].get<double>());
  // After the flow steps: the pressure solver's tolerance (rtol 1e-6) moves the grains' last bits.
  for (const char* k : {"crater_a", "crater_b", "bed_porosity"})
    EXPECT_NEAR(a[k].get<double>(), b[k].get<double>(), 1e-9) << k;
}

TEST(DropOnSand, RestartContinuesTheCraterSeries) {
  const std::string dir = kDir + "/restart";
  const auto straight = drop_run(world_size(), {"run.max_steps=8"}, kDir + "/straight");
  drop_run(world_size(), {"run.max_steps=4"}, dir);
  const auto resumed = drop_run(world_size(), {"run.max_steps=8"}, dir, dir + "/checkpoint.h5");
  if (world_rank() != 0) return;
  const auto &a = straight["quantities"], &b = resumed["quantities"];
  for (const char* k : {"crater_volume", "crater_volume_start", "crater_a", "crater_b", "bed_porosity",
                        "bed_porosity_start", "bed_top"})
    EXPECT_EQ(a[k].get<double>(), b[k].get<double>()) << k;
  // crater.csv: the straight run's rows, bit for bit (the restart adds no row at its start). The case
  // does not land on the snapshot times (output.land_on_times: false): the stopped run's last step
  // fired the snapshot due within half a step after it, and the resumed run must not fire it again.
  EXPECT_EQ(test::file_text(dir + "/crater.csv"), test::file_text(kDir + "/straight/crater.csv"));
  EXPECT_GE(row_times(dir + "/crater.csv").size(), 4u);
}

TEST(DropOnSand, RefusesADropInTheBed) {
  EXPECT_THROW(
      {
        try {
          drop_run(world_size(), {"run.max_steps=1", "drop.centre_above_bed=1 mm"}, kDir + "/refused");
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("centre_above_bed"), std::string::npos) << e.what();
          throw;
        }
      },
      InputError);
}

TEST(DropOnSand, RefusesABodyOutsideTheBox) {
  // The bed's second lattice layer lies above a lid at 2.6 mm (a bed made in a taller box, or a grain
  // still in flight above the impact's lid): refused at set-up, naming the body, before any output.
  const std::string top = "[33.8 mm, 33.8 mm, 2.6 mm]";
  EXPECT_THROW(
      {
        try {
          drop_run(world_size(), {"run.max_steps=1", "domain.box_max=" + top, "solid.walls.0.max=" + top},
                   kDir + "/outside");
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("outside the domain"), std::string::npos) << e.what();
          EXPECT_NE(std::string(e.what()).find("body "), std::string::npos) << e.what();
          throw;
        }
      },
      InputError);
  EXPECT_FALSE(fs::exists(kDir + "/outside/summary.json"));
}

TEST(DropOnSand, BedFallsAtFourGUntilTheTopGrainLands) {
  const std::vector<std::string> common = {"deposition.max_grains=200", "output.snapshot_interval=0",
                                           "output.progress_interval=1000"};
  // In 0.4 ms at 4 g a grain falls 3.1 um: no grain reaches the floor (the lowest bottom starts at
  // least 1.295 - 0.02 - 1.27 mm = 5 um above it) or another (the lattice's gaps are fixed while all
  // fall alike): all fall freely at 4 g.
  auto early = common;
  early.insert(early.end(), {"run.end_time=0.4 ms", "run.check_interval=0.4 ms"});
  const auto a = test::run_case_on(world_size(), cases("bed_small.yaml"), early, kDir + "/fall_early");
  auto full = common;
  full.push_back("deposition.after_landing=1 ms");
  const auto b = test::run_case_on(world_size(), cases("bed_small.yaml"), full, kDir + "/fall_full");
  if (world_rank() != 0) return;
  const double g = 9.8, t = a["time"].get<double>();
  EXPECT_NEAR(a["quantities"]["mean_speed"].get<double>(), 4 * g * t, 1e-9 * g * t);
  EXPECT_LT(a["quantities"]["landing_time"].get<double>(), 0);  // not yet
  const double landing = b["quantities"]["landing_time"].get<double>();
  EXPECT_GT(landing, 0.5e-3);
  EXPECT_EQ(b["status"], "completed");
  EXPECT_NEAR(b["time"].get<double>(), landing + 1e-3, 0.5e-3);  // checked every run.check_interval
  std::printf("  mean speed at %.2g ms %.6g m/s (4 g t = %.6g); landing at %.4g s\n", t * 1e3,
              a["quantities"]["mean_speed"].get<double>(), 4 * g * t, landing);
}
