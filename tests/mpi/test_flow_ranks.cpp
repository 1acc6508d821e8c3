// SPDX-License-Identifier: MIT
// The flow scene on 1, 2 and 4 ranks (process grids 1x1x1, 2x1x1 / 1x1x2, 2x2x1, 1x1x4): the same
// drop falling into a pool gives the same fields up to the Poisson tolerance (the advection and
// the multigrid smoother are decomposition independent; only the CG dot products are summed in a
// rank-dependent order); the same with gravity off the grid's axes on 1 and 4 ranks. Restart: a run stopped and resumed from its checkpoint ends bit for bit
// where the straight run ends, at the same rank count, and within the tolerance at another. The
// Taylor-Green vortex and the dam break (issue 18) on 4 ranks against 1; the heavy drop in a
// periodic box on 1 and 4 ranks.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/decomposition.hpp"
#include "core/h5_file.hpp"
#include "fluid/flow_solver.hpp"
#include "support/flow_shapes.hpp"
#include "support/taylor_green.hpp"
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

TEST(FlowRanks, RebalancingMovesUnevenCutsAndKeepsTheFields) {
  // Four ranks (2 x 2 x 1) with the cuts put by hand at x = 2.5 mm and y = 5.5 mm (5 and 11 cells
  // of 16 each way: 1,210 cells on the busiest rank against 1,024 on average). With `balance` every
  // 3 steps (issue 19; a flow cell is the work) the cuts move back to 4 mm after step 3 and the
  // grid, its fields and its multigrid follow; the measured-time variant moves them where the ranks'
  // busy seconds say. Both end as the 1-rank run does, to the Poisson tolerance (the other tests'
  // bound).
  const auto s1 = run_on(1, {}, kDir + "/bal1");
  const std::vector<std::string> uneven = {"domain.process_grid=[2,2,1]", "domain.cuts.x=[2.5 mm]",
                                           "domain.cuts.y=[5.5 mm]", "balance.enabled=true",
                                           "balance.interval=3", "balance.threshold=1.0"};
  const auto counts = run_on(4, uneven, kDir + "/bal4");
  auto timed = uneven;
  timed.push_back("balance.measure=time");
  const auto time = run_on(4, timed, kDir + "/bal4t");
  if (world_rank() != 0) return;
  const auto& rec = counts["balance"];
  std::printf("counts: %ld rebalances, imbalance %.3f -> %.3f, cuts x %s y %s, cells per rank %s\n",
              rec["rebalances"].get<long>(), rec["first_imbalance"].get<double>(), counts["imbalance"].get<double>(),
              counts["cuts"][0].dump().c_str(), counts["cuts"][1].dump().c_str(), counts["per_rank"]["cells"].dump().c_str());
  std::printf("time: %ld rebalances, cuts x %s y %s\n", time["balance"]["rebalances"].get<long>(),
              time["cuts"][0].dump().c_str(), time["cuts"][1].dump().c_str());
  EXPECT_EQ(rec["rebalances"].get<long>(), 1);  // then balanced: no cut moves
  EXPECT_EQ(rec["events"][0]["step"].get<long>(), 3);
  EXPECT_NEAR(rec["first_imbalance"].get<double>(), 11.0 * 11 / 64, 1e-12);  // 11 x 11 columns of 16 x 16
  EXPECT_EQ(counts["imbalance"].get<double>(), 1.0);
  for (const auto& c : counts["per_rank"]["cells"]) EXPECT_EQ(c.get<long>(), 1024);
  EXPECT_GE(time["balance"]["rebalances"].get<long>(), 1);
  const Fields ref = read_fields(kDir + "/bal1/checkpoint.h5");
  const double vmax = s1["quantities"]["max_speed"].get<double>();
  for (const char* d : {"bal4", "bal4t"}) {
    const Fields other = read_fields(kDir + "/" + std::string(d) + "/checkpoint.h5");
    const double df = max_diff(ref.f, other.f), du = max_diff(ref.u, other.u);
    std::printf("%s vs 1 rank after 30 steps: max |df| %.2e, max |du| %.2e m/s\n", d, df, du);
    EXPECT_LT(df, 1e-8) << d;
    EXPECT_LT(du, 1e-8 * vmax) << d;
    EXPECT_FALSE(fs::exists(kDir + "/" + std::string(d) + "/repartition.h5"));
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

namespace {

// The heavy drop of the seed's size (5.5 mm, water in air, 1000 : 1, both viscous, no gravity)
// moving at 1 m/s through still air in a periodic 2 cm box, on a communicator: the total
// momentum, the drop's (liquid) momentum and kinetic energy, and its extent across the motion after
// each step.
struct HeavyDrop {
  std::vector<double> total, drop, energy, energy_all;  // x-momentum of all, of the liquid; the liquid's KE, all KE
  std::vector<double> extent;  // the liquid's rms extent across the motion (y)
  double volume0 = 0, volume = 0, extent0 = 0;
  double travelled = 0;
};

HeavyDrop periodic_heavy_drop(MPI_Comm comm, int steps) {
  Decomposition decomp(comm, {0, 0, 0}, {0.02, 0.02, 0.02});
  FlowSettings st;
  st.cells = {24, 24, 24};
  for (auto& b : st.boundaries) b = {BoundaryKind::periodic, BoundaryKind::periodic};
  st.gravity = {};
  st.poisson.rtol = 1e-10;
  FlowSolver s(decomp, st);
  const Vec3 centre{0.01, 0.01, 0.01};
  auto inside = [&](const Vec3& p) { return dot(p - centre, p - centre) < 0.0055 * 0.0055 / 4; };
  s.initialize([&](int i, int j, int k) {
    const double f = test::sampled_fraction(s.grid(), i, j, k, inside);
    return FlowSolver::CellState{f, {f > 0 ? 1.0 : 0.0, 0, 0}};  // mass-averaged: the drop's cells move
  });
  const FluidGrid& g = s.grid();
  auto sums = [&](double out[6]) {  // P_x, P_x of the liquid, KE of the liquid, V_liquid, sum f V (y - y_c)^2
    double local[6] = {0, 0, 0, 0, 0, 0};
    for (int k = g.begin(2); k < g.end(2); ++k)
      for (int j = g.begin(1); j < g.end(1); ++j)
        for (int i = g.begin(0); i < g.end(0); ++i) {
          const std::size_t c = g.at(i, j, k);
          const double f = s.fraction()[c], u = s.velocity(0)[c], m = s.density()[c] * g.cell_volume();
          const double ml = st.liquid.density * f * g.cell_volume();
          double speed2 = 0;
          for (int d = 0; d < 3; ++d) speed2 += s.velocity(d)[c] * s.velocity(d)[c];
          local[0] += m * u;
          local[1] += ml * u;
          local[2] += 0.5 * ml * speed2;
          local[5] += 0.5 * m * speed2;
          local[3] += f * g.cell_volume();
          const Vec3 x = g.centre(i, j, k);
          local[4] += f * g.cell_volume() * (x.y - centre.y) * (x.y - centre.y);
        }
    MPI_Allreduce(local, out, 6, MPI_DOUBLE, MPI_SUM, comm);
  };
  HeavyDrop out;
  double v[6];
  sums(v);
  out.volume0 = v[3];
  out.extent0 = std::sqrt(v[4] / v[3]);
  double t = 0;
  for (int n = 0; n < steps; ++n) {
    std::string limit;
    const double dt = std::min(s.stable_dt(limit), 2e-4);
    s.advance(dt);
    t += dt;
    sums(v);
    out.total.push_back(v[0]);
    out.drop.push_back(v[1]);
    out.energy.push_back(v[2]);
    out.energy_all.push_back(v[5]);
    out.extent.push_back(std::sqrt(v[4] / v[3]));
  }
  out.volume = v[3];
  out.travelled = t * 1.0;
  return out;
}

}  // namespace

TEST(FlowRanks, HeavyDropCrossesAPeriodicBoxConservingMomentum) {
  // Issue 18. No walls, no gravity: the total momentum is conserved by the scheme in one fluid
  // (C8's flow test) and here, across the 1000 : 1 interface, up to F10's density-jump residual,
  // which a drive-free drop keeps small: bound 1e-9 of the momentum (measured 2.1e-14). The drop
  // loses momentum only to the air. Energy: with no drive the whole kinetic energy can only fall
  // (viscous dissipation). F7's bounded limited flux keeps every new velocity inside its
  // neighbours' range, but unlike plain upwind it is not energy stable step by step: checked is
  // the integral law, the whole energy never above its start (no source) and both it and the
  // drop's lower after every crossing than before (the rises at single steps are reported:
  // measured twice, by 6e-5 of the energy, in the first 10 steps while the impulsive start's
  // velocity jump at the interface is smoothed). The drop's volume is kept to round-off. Shape:
  // no surface tension holds it, so the air's stagnation pressure flattens it; over three box
  // crossings (60 ms, T* = t U / D sqrt(rho_g / rho_l) = 0.35) its rms extent across the motion
  // grows at every crossing (1.25 -> 1.30, 1.39, 1.49 mm, measured), a guard bounds it at 1.5
  // times the start (the drop stays one compact body). 1 and 4 ranks agree to 1e-6 of the
  // momentum (the Poisson tolerance through CG's rank-ordered sums; measured 0 to 1.4e-19).
  const int rank = test::world_rank();
  const int steps = 300;
  const HeavyDrop four = periodic_heavy_drop(MPI_COMM_WORLD, steps);
  const HeavyDrop one = periodic_heavy_drop(MPI_COMM_SELF, steps);
  if (rank != 0) return;
  const double p0 = one.total.front();
  double drift = 0, rank_diff = 0;
  int energy_rises = 0;
  double largest_rise = 0, highest = 0;  // of the whole kinetic energy
  for (int n = 0; n < steps; ++n) {
    drift = std::max(drift, std::abs(one.total[n] - p0));
    rank_diff = std::max(rank_diff, std::abs(one.drop[n] - four.drop[n]));
    energy_rises += n > 0 && one.energy_all[n] > one.energy_all[n - 1];
    largest_rise = std::max(largest_rise, n > 0 ? (one.energy_all[n] - one.energy_all[n - 1]) / one.energy_all[n] : 0.0);
    highest = std::max(highest, one.energy_all[n]);
  }
  std::printf("heavy drop, %d steps (%.3g box lengths): total momentum drift %.3e of %.4e kg m/s (%.1e); drop momentum %.4e -> %.4e; "
              "KE rises %d times (largest %.1e of it); volume %.3e; rms extent across %.4f mm at the start, %.4f %.4f %.4f after 1, 2, 3 crossings; 1 vs 4 ranks %.3e\n",
              steps, one.travelled / 0.02, drift, p0, drift / p0, one.drop.front(), one.drop.back(), energy_rises, largest_rise,
              (one.volume - one.volume0) / one.volume0, one.extent0 * 1e3, one.extent[99] * 1e3, one.extent[199] * 1e3,
              one.extent[299] * 1e3, rank_diff);
  EXPECT_LT(drift, 1e-9 * p0);
  EXPECT_LT(one.drop.back(), one.drop.front());
  EXPECT_LE(highest, one.energy_all.front());
  for (int n : {99, 199, 299}) {
    EXPECT_LT(one.energy_all[n], one.energy_all[n - 99]);
    EXPECT_LT(one.energy[n], one.energy[n - 99]);
  }
  EXPECT_LT(std::abs(one.volume - one.volume0), 1e-12 * one.volume0);
  EXPECT_GT(one.extent[99], one.extent0);
  EXPECT_GT(one.extent[199], one.extent[99]);
  EXPECT_GT(one.extent[299], one.extent[199]);
  EXPECT_LT(one.extent[299], 1.5 * one.extent0);
  EXPECT_LT(rank_diff, 1e-6 * p0);
}

namespace {

// The Taylor-Green vortex (test_flow.cpp's, 32^2, one fluid, periodic, nu = 0.05, Poisson rtol
// 1e-12) on a communicator with the given process grid: u and v of every cell at t = 0.5, in global
// cell order, on every rank of the communicator.
std::vector<double> taylor_green_velocity(MPI_Comm comm, std::array<int, 3> dims) {
  const int n = 32;
  Decomposition decomp(comm, {0, 0, 0}, {test::kTaylorGreenL, test::kTaylorGreenL, test::kTaylorGreenL / n}, dims);
  const auto solver = test::taylor_green(decomp, n, 0.05);
  FlowSolver& s = *solver;
  const FluidGrid& g = s.grid();
  test::advance_taylor_green(s, n, 0.5);
  std::vector<double> field(2 * n * n, 0.0);
  for (int j = g.begin(1); j < g.end(1); ++j)
    for (int i = g.begin(0); i < g.end(0); ++i) {
      const std::size_t c = g.at(i, j, 0);
      field[2 * (j * n + i)] = s.velocity(0)[c];
      field[2 * (j * n + i) + 1] = s.velocity(1)[c];
    }
  MPI_Allreduce(MPI_IN_PLACE, field.data(), static_cast<int>(field.size()), MPI_DOUBLE, MPI_SUM, comm);
  return field;
}

Fields read_fields(const std::string& path, std::size_t nx, std::size_t ny, std::size_t nz) {
  H5File h = H5File::open_read(path, MPI_COMM_SELF);
  const std::size_t g[3] = {nz, ny, nx}, o[3] = {0, 0, 0};  // the file holds z, y, x
  return {h.read_block("liquid_fraction", g, o, g, 1), h.read_block("velocity", g, o, g, 3),
          h.read_block("pressure", g, o, g, 1)};
}

}  // namespace

// Issue 18: the single-phase and the 1000 : 1 verification cases on 4 ranks agree with 1 rank to
// the Poisson tolerance. The advection and the smoother are decomposition independent; only CG's
// dot products are summed in a rank-dependent order, so the fields differ by what the tolerance
// lets through each step (rtol 1e-12 here: 1e-12 of the velocity scale per step, about 50 steps).
TEST(FlowRanks, TaylorGreenOnOneAndFourRanks) {
  const auto four = taylor_green_velocity(MPI_COMM_WORLD, {2, 2, 1});
  const auto one = taylor_green_velocity(MPI_COMM_SELF, {1, 1, 1});
  if (test::world_rank() != 0) return;
  const double du = max_diff(one, four);
  std::printf("Taylor-Green 32^2 at t = 0.5, 4 ranks (2x2) vs 1: max |du| %.2e (velocity scale 1)\n", du);
  EXPECT_LT(du, 1e-9);
}

// The dam break (the shipped case, cases/dam_break/martin_moyce.yaml, 128 x 128) to t = 0.1 s (the
// front has run 1.7 column widths) with the pressure solved to 1e-11: 1 rank against 4 (2x2).
// The front position is the experiment's quantity; the fields bound everything else. Bound 1e-8
// (as the impact above): the tolerance's 1e-11 per step over the run's 100 steps, with room for
// growth (measured 1.2e-14 in f, 1.8e-14 m/s in u; the Taylor-Green field 3.3e-16).
TEST(FlowRanks, DamBreakOnOneAndFourRanks) {
  const std::string text = test::file_text(TESSERA_SOURCE_DIR "/cases/dam_break/martin_moyce.yaml");
  const std::vector<std::string> sets = {"run.end_time=0.1", "fluid.poisson.rtol=1e-11", "output.snapshot_interval=0",
                                         "output.series_interval=0.1"};
  auto with = [&](std::vector<std::string> s, const std::string& grid) {
    s.push_back("domain.process_grid=" + grid);
    return s;
  };
  const auto s1 = test::run_case_on(1, text, with(sets, "[1,1,1]"), kDir + "/dam1");
  const auto s4 = test::run_case_on(4, text, with(sets, "[2,2,1]"), kDir + "/dam4");
  if (test::world_rank() != 0) return;
  const Fields a = read_fields(kDir + "/dam1/checkpoint.h5", 128, 128, 1);
  const Fields b = read_fields(kDir + "/dam4/checkpoint.h5", 128, 128, 1);
  const double vmax = s1["quantities"]["max_speed"].get<double>();
  const double df = max_diff(a.f, b.f), du = max_diff(a.u, b.u);
  const double front1 = s1["quantities"]["front_position"].get<double>();
  const double front4 = s4["quantities"]["front_position"].get<double>();
  std::printf("dam break 128^2 to t = 0.1 s (%ld steps), 4 ranks vs 1: max |df| %.2e, max |du| %.2e m/s (max speed "
              "%.2f m/s); front %.6f vs %.6f m\n",
              s1["steps"].get<long>(), df, du, vmax, front1, front4);
  EXPECT_LT(df, 1e-8);
  EXPECT_LT(du, 1e-8 * vmax);
  EXPECT_LT(std::abs(front1 - front4), 1e-8);
}
