// SPDX-License-Identifier: MIT
// The blast's bond dashpots solved all together (src/fracture/fracture_damping.cpp; docs/theory.md
// B9a) against what they must do exactly:
//   - two mirror-image tetrahedra closing along their bond's normal with (almost) no spring: after
//     each step their relative speed is the theta method's u (1 - (1 - theta) x) / (1 + theta x),
//     x = h c / mu (c = c_n A, mu the reduced mass), to 1e-9, at x = 5, two and a half times the
//     explicit dashpot's stability limit, for backward Euler and for the trapezoidal rule; no
//     rotation, momentum kept to round-off;
//   - the bar shattered by a fast impact (test_blast_bonds), with the dashpots implicit, on uniform
//     steps and on the stability levels of the springs that act: the same bits on 1, 2 and 4 ranks
//     (the solve's inner products are exact sums), faces broken and pairs touching, and the
//     momentum of the start kept to round-off (every impulse, the dashpots' too, is pairwise).
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "fracture/fracture_solver.hpp"
#include "solid/gmsh_reader.hpp"

namespace tessera {
namespace {

struct World {
  Decomposition decomp;
  FractureSolver solver;
  World(MPI_Comm comm, const TetMesh& mesh, FractureSettings s, Vec3 lo, Vec3 hi)
      : decomp(comm, lo, hi), solver(decomp, build_bonded_block(mesh, s.density), s, std::nullopt) {}
};

TEST(ImplicitDashpots, ClosingPairFollowsTheThetaMethodWellPastTheExplicitLimit) {
  const double a = 0.05, h = 0.04;
  TetMesh mesh;
  mesh.nodes = {{0, 0, 0}, {a, 0, 0}, {0, a, 0}, {a / 3, a / 3, h}, {a / 3, a / 3, -h}};
  mesh.tetrahedra = {{0, 1, 2, 3}, {0, 2, 1, 4}};
  for (const double theta : {1.0, 0.5}) {
    FractureSettings s;
    // Springs a trillionth of the seed's: the dashpots alone move the pair.
    s.bond.kn = s.bond.ks = 1e-3;
    s.bond.tensile_strength = 1e-3;
    s.implicit_damping = true;
    s.damping_theta = theta;
    s.damping_rtol = 1e-13;
    const BondedBlock probe = build_bonded_block(mesh, s.density);
    const double mu = probe.mass[0] * probe.mass[1] / (probe.mass[0] + probe.mass[1]);
    const double c = s.bond.cn * probe.bonds[0].area, x = 5.0;
    s.time_step = x * mu / c;  // the explicit dashpot is stable for x < 2
    World w(MPI_COMM_SELF, mesh, s, {-1, -1, -1}, {1, 1, 1});
    FractureSolver& f = w.solver;
    const double v0 = 0.3;
    for (std::size_t e = 0; e < 2; ++e) f.set_velocity(e, {0, 0, f.block().x0[e].z > 0 ? -v0 : v0}, {});
    f.setup();
    const Vec3 p0 = f.v()[0] * f.block().mass[0] + f.v()[1] * f.block().mass[1];
    const double r = (1 - (1 - theta) * x) / (1 + theta * x);
    double u = f.v()[1].z - f.v()[0].z;
    for (int step = 0; step < 4; ++step) {
      f.step();
      const double u_new = f.v()[1].z - f.v()[0].z;
      std::printf("theta %.1f, step %d: u %.12g, ratio %.12g (theta method %.12g)\n", theta, step, u_new, u_new / u, r);
      EXPECT_NEAR(u_new / u, r, 1e-6) << "theta " << theta << ", step " << step;
      u = u_new;
    }
    EXPECT_EQ(f.broken_count(), 0);
    const Vec3 p = f.v()[0] * f.block().mass[0] + f.v()[1] * f.block().mass[1];
    EXPECT_LT(norm(p - p0), 1e-15 * probe.mass[0] * v0);
    EXPECT_LT(norm(f.w()[0]) + norm(f.w()[1]), 1e-9 * v0 / a) << "no rotation from a centred push";
    EXPECT_GT(f.damping_solves(), 0);
  }
}

// A bar of nx x ny x nz cubes of side h, each split into 6 tetrahedra around its main diagonal.
TetMesh bar_mesh(int nx, int ny, int nz, double h) {
  TetMesh m;
  auto node = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) m.nodes.push_back({i * h, j * h, k * h});
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : perms) {
          int c[3] = {0, 0, 0};
          std::array<int, 4> t{};
          t[0] = node(i, j, k);
          for (int s = 0; s < 3; ++s) {
            c[p[s]] = 1;
            t[static_cast<std::size_t>(s) + 1] = node(i + c[0], j + c[1], k + c[2]);
          }
          m.tetrahedra.push_back(t);
        }
  return m;
}

TEST(ImplicitDashpots, ShatteringGivesTheSameBitsOnAnyRankCountAndKeepsMomentum) {
  int size = 1, rank = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const double h = 0.02;
  const TetMesh mesh = bar_mesh(10, 3, 2, h);
  const Vec3 lo{-0.01, -0.01, -0.01}, hi{0.21, 0.07, 0.05};
  for (const Stepping stepping : {Stepping::uniform, Stepping::stability}) {
    FractureSettings s;
    s.stepping = stepping;
    s.implicit_damping = true;
    s.damping_theta = 0.5;
    // Uniform steps past the explicit scheme's (B9's bound, 6.4e-8 s here).
    if (stepping == Stepping::uniform) s.time_step = 2e-7;
    auto run = [&](MPI_Comm comm) {
      auto w = std::make_unique<World>(comm, mesh, s, lo, hi);
      FractureSolver& f = w->solver;
      for (std::size_t e = 0; e < f.block().size(); ++e)
        if (f.block().x0[e].x < 2 * h) f.set_velocity(e, {-60, 5, 0}, {0, 0, 300});
      f.setup();
      f.sync_state();
      Vec3 p0{};
      for (std::size_t e = 0; e < f.block().size(); ++e) p0 += f.v()[e] * f.block().mass[e];
      int finest = 0;
      for (int i = 0; i < 600; ++i) {
        f.step();
        for (int k : f.levels()) finest = std::max(finest, k);
      }
      f.sync_state();
      return std::make_tuple(std::move(w), finest, p0);
    };
    auto [here, finest, p0] = run(MPI_COMM_WORLD);
    auto alone = std::get<0>(run(MPI_COMM_SELF));
    const FractureSolver &a = here->solver, &b = alone->solver;
    const char* name = stepping == Stepping::uniform ? "uniform" : "stability";
    if (stepping == Stepping::stability) {
      EXPECT_GE(finest, 1) << "sub-steps (more than one level)";
    }
    EXPECT_GT(a.broken_count(), 5) << name;
    EXPECT_GT(a.contact_evaluations() + b.contact_evaluations(), 0) << name;
    EXPECT_EQ(a.broken_count(), b.broken_count()) << name;
    EXPECT_EQ(a.damping_solves(), b.damping_solves()) << name;
    EXPECT_EQ(a.damping_iterations(), b.damping_iterations()) << name;
    Vec3 p{};
    for (std::size_t e = 0; e < a.block().size(); ++e) {
      p += a.v()[e] * a.block().mass[e];
      ASSERT_EQ(a.x()[e].x, b.x()[e].x) << name << ", element " << e << " on " << size << " ranks, rank " << rank;
      ASSERT_EQ(a.x()[e].y, b.x()[e].y) << name;
      ASSERT_EQ(a.v()[e].z, b.v()[e].z) << name;
      ASSERT_EQ(a.q()[e].w, b.q()[e].w) << name;
      ASSERT_EQ(a.angular_momentum()[e].z, b.angular_momentum()[e].z) << name;
    }
    std::printf("%s: %ld faces, %ld damping solves (%.1f iterations each), momentum change %.3g of %.3g\n", name,
                a.broken_count(), a.damping_solves(),
                static_cast<double>(a.damping_iterations()) / std::max(1L, a.damping_solves()), norm(p - p0), norm(p0));
    EXPECT_LT(norm(p - p0), 1e-12 * norm(p0)) << name;
  }
}

}  // namespace
}  // namespace tessera
