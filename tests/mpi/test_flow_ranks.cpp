// SPDX-License-Identifier: MIT
// The flow scene on 1, 2 and 4 ranks (process grids 1x1x1, 2x1x1 / 1x1x2, 2x2x1, 1x1x4): the same
// drop falling into a pool gives the same fields up to the Poisson tolerance (the advection and
// the multigrid smoother are decomposition independent; only the CG dot products are summed in a
// rank-dependent order); the same with gravity off the grid's axes on 1 and 4 ranks. Restart: a run stopped and resumed from its checkpoint ends bit for bit
// where the straight run ends, at the same rank count, and within the tolerance at another.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/h5_file.hpp"
#include "support/scene_runs.hpp"

using namespace tessera;
using tessera::test::world_rank;
namespace fs = std::filesystem;

namespace {

const char* kCase = R"(
scene: flow
domain: {box_min: [0, 0, 0], box_max: [8 mm, 8 mm, 8 mm]}
fluid:
  cells: [16, 16, 16]
  liquid: {density: 1000, viscosity: 1.0e-3 Pa*s}
  gas: {density: 1.0, viscosity: 1.8e-5 Pa*s}
  boundaries: {z_high: outflow}
  poisson: {rtol: 1e-11}
initial:
  liquid:
    - box: {min: [0, 0, 0], max: [8 mm, 8 mm, 3 mm]}
    - sphere: {centre: [4.3 mm, 3.8 mm, 5.2 mm], radius: 1.5 mm, velocity: [0.3, 0, -2.5]}
run: {end_time: 1 s, max_steps: 30}
)";

// Runs the case on the first `ranks` ranks of the world; returns the summary on those ranks.
nlohmann::json run_on(int ranks, const std::vector<std::string>& sets, const std::string& dir,
                      std::optional<std::string> restart = {}) {
  return test::run_case_on(ranks, kCase, sets, dir, restart);
}

struct Fields {
  std::vector<double> f, u, p;
};

Fields read_fields(const std::string& path) {
  H5File h = H5File::open_read(path, MPI_COMM_SELF);
  const std::size_t g[3] = {16, 16, 16}, o[3] = {0, 0, 0};
  return {h.read_block("liquid_fraction", g, o, g, 1), h.read_block("velocity", g, o, g, 3),
          h.read_block("pressure", g, o, g, 1)};
}

double max_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

const std::string kDir = "flow_ranks_out";

}  // namespace

TEST(FlowRanks, SameFieldsOnOneTwoFourRanks) {
  const auto s1 = run_on(1, {}, kDir + "/np1");
  run_on(2, {"domain.process_grid=[2,1,1]"}, kDir + "/np2x");
  run_on(2, {"domain.process_grid=[1,1,2]"}, kDir + "/np2z");
  run_on(4, {"domain.process_grid=[2,2,1]"}, kDir + "/np4");
  run_on(4, {"domain.process_grid=[1,1,4]"}, kDir + "/np4z");
  if (world_rank() == 0) {
    EXPECT_LT(std::abs(s1["quantities"]["liquid_volume_drift"].get<double>()), 1e-12);
    const Fields ref = read_fields(kDir + "/np1/checkpoint.h5");
    const double vmax = s1["quantities"]["max_speed"].get<double>();
    for (const char* d : {"np2x", "np2z", "np4", "np4z"}) {
      const Fields other = read_fields(kDir + "/" + d + "/checkpoint.h5");
      const double df = max_diff(ref.f, other.f), du = max_diff(ref.u, other.u);
      std::printf("%s vs 1 rank after 30 steps: max |df| %.2e, max |du| %.2e m/s (max speed %.2f m/s)\n", d, df, du,
                  vmax);
      // Poisson rtol 1e-11: differences of that order, grown over 30 steps of an impact.
      EXPECT_LT(df, 1e-8) << d;
      EXPECT_LT(du, 1e-8 * vmax) << d;
    }
  }
}

TEST(FlowRanks, TiltedGravitySameOnOneAndFourRanks) {
  // Gravity off the grid's axes: every interface face takes the interface's gravity potential
  // (theory F10b), from height functions whose columns and ghost exchange cross the cuts.
  const std::string g = "fluid.gravity=[3.0, 1.5, -9.2]";
  const auto s1 = run_on(1, {g}, kDir + "/tilt1");
  run_on(4, {g, "domain.process_grid=[2,2,1]"}, kDir + "/tilt4");
  if (world_rank() == 0) {
    const Fields a = read_fields(kDir + "/tilt1/checkpoint.h5"), b = read_fields(kDir + "/tilt4/checkpoint.h5");
    const double vmax = s1["quantities"]["max_speed"].get<double>();
    const double df = max_diff(a.f, b.f), du = max_diff(a.u, b.u);
    std::printf("tilted gravity, 4 ranks vs 1 after 30 steps: max |df| %.2e, max |du| %.2e m/s (max speed %.2f m/s)\n",
                df, du, vmax);
    EXPECT_LT(df, 1e-8);
    EXPECT_LT(du, 1e-8 * vmax);
  }
}

TEST(FlowRanks, RestartIsBitwiseAtTheSameRankCount) {
  run_on(2, {}, kDir + "/straight");
  run_on(2, {"run.max_steps=13"}, kDir + "/first");
  if (world_rank() == 0)
    fs::copy_file(kDir + "/first/checkpoint.h5", kDir + "/resume.h5", fs::copy_options::overwrite_existing);
  MPI_Barrier(MPI_COMM_WORLD);
  run_on(2, {}, kDir + "/second", kDir + "/resume.h5");
  run_on(4, {}, kDir + "/second4", kDir + "/resume.h5");
  if (world_rank() == 0) {
    const Fields a = read_fields(kDir + "/straight/checkpoint.h5"), b = read_fields(kDir + "/second/checkpoint.h5");
    EXPECT_EQ(max_diff(a.f, b.f), 0.0);
    EXPECT_EQ(max_diff(a.u, b.u), 0.0);
    EXPECT_EQ(max_diff(a.p, b.p), 0.0);
    const Fields c = read_fields(kDir + "/second4/checkpoint.h5");
    EXPECT_LT(max_diff(a.f, c.f), 1e-8);
    EXPECT_LT(max_diff(a.u, c.u), 1e-8);
  }
}
