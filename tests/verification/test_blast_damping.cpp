// SPDX-License-Identifier: MIT
// The blast's bond dashpots solved all together (src/fracture/fracture_damping.cpp; docs/theory.md
// B9a) against what they must do exactly:
//   - two mirror-image tetrahedra closing along their bond's normal with (almost) no spring: after
//     each step their relative speed is the theta method's u (1 - (1 - theta) x) / (1 + theta x),
//     x = h c / mu (c = c_n A, mu the reduced mass), to 1e-9, at x = 5, two and a half times the
//     explicit dashpot's stability limit, for backward Euler and for the trapezoidal rule; no
//     rotation, momentum kept to round-off;
//   - the same bits on 1, 2 and 4 ranks and momentum to round-off with the solve: test_blast_bonds'
//     shattered bar (BondedBar.ShatteringGivesTheSameBitsOnAnyRankCount).
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "fracture/fracture_solver.hpp"
#include "solid/gmsh_reader.hpp"
#include "support/fracture_fixture.hpp"

namespace tessera {
namespace {

using World = test::FractureWorld;


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


}  // namespace
}  // namespace tessera
