// SPDX-License-Identifier: MIT
// The blast's bond dashpots solved all together (src/fracture/fracture_damping.cpp; docs/theory.md
// B9a) against what they must do exactly:
//   - two mirror-image tetrahedra closing along their bond's normal with (almost) no spring: after
//     each step their relative speed is the theta method's u (1 - (1 - theta) x) / (1 + theta x),
//     x = h c / mu (c = c_n A, mu the reduced mass), to 1e-9, at x = 5, two and a half times the
//     explicit dashpot's stability limit, for backward Euler and for the trapezoidal rule, on
//     uniform steps and on the stability levels; solved every second step (B9c), the speed is kept
//     between the solves and each solve is the theta method's at 2 x; no rotation, momentum kept
//     to round-off;
//   - the same bits on 1, 2 and 4 ranks and momentum to round-off with the solve: test_blast_bonds'
//     shattered bar (BondedBar.ShatteringGivesTheSameBitsOnAnyRankCount);
//   - B9b's matrix at frozen orientations: a bar spinning through 0.2 rad (5e-5 rad a step), whose
//     stretching, added after 0.15 rad, dashpots ten times the seed's damp, ends within 10 x the
//     angle (1e-4) times what the dashpots did of the run whose matrix follows every turn (angle 0);
//     a setting never reached (10 rad) stays within 1e-3 of it by each element's cap (without the
//     cap the matrix stays at the start's orientations and the run goes unstable).
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
  // Each theta on uniform steps and on the stability levels (one level here), the dashpots solved
  // every step and every second step (B9c: over two steps at once, x doubled, and nothing between).
  for (const double theta : {1.0, 0.5})
  for (const Stepping stepping : {Stepping::uniform, Stepping::stability})
  for (const int interval : {1, 2}) {
    FractureSettings s;
    s.stepping = stepping;
    s.damping_interval = interval;
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
    const double X = interval * x;  // the solve's h c / mu
    double u = f.v()[1].z - f.v()[0].z;
    for (int step = 1; step <= 4; ++step) {
      f.step();
      const double u_new = f.v()[1].z - f.v()[0].z;
      const double r = step % interval == 0 ? (1 - (1 - theta) * X) / (1 + theta * X) : 1.0;
      std::printf("theta %.1f, interval %d, step %d: u %.12g, ratio %.12g (theta method %.12g)\n", theta, interval,
                  step, u_new, u_new / u, r);
      EXPECT_NEAR(u_new / u, r, 1e-6) << "theta " << theta << ", interval " << interval << ", step " << step;
      u = u_new;
    }
    EXPECT_EQ(f.broken_count(), 0);
    const Vec3 p = f.v()[0] * f.block().mass[0] + f.v()[1] * f.block().mass[1];
    EXPECT_LT(norm(p - p0), 1e-15 * probe.mass[0] * v0);
    EXPECT_LT(norm(f.w()[0]) + norm(f.w()[1]), 1e-9 * v0 / a) << "no rotation from a centred push";
    EXPECT_GT(f.damping_solves(), 0);
  }
}

TEST(FrozenDashpotMatrix, SpinningBarIsDampedAsWithTheMatrixOfEveryTurn) {
  const double a = 0.05;
  const TetMesh mesh = test::bar_mesh(3, 1, 1, a);  // 18 tetrahedra, 15 cm along x
  const double stretch = 1.0;                       // m/s end to end, added after 0.15 rad of spin
  auto run = [&](double angle, bool damping = true) {
    FractureSettings s;
    s.damping = damping;
    // Strong enough not to break under the spin's pull (sigma_f < sqrt(2 G_f k_n) holds).
    s.bond.tensile_strength = 1e9, s.bond.cohesion = 1e9, s.bond.fracture_energy = 1e7;
    // Dashpots ten times the seed's: as far past critical as the seed's on 5 mm elements (B9), where
    // the solve's matrix, not only its right-hand side, makes the change.
    s.bond.cn *= 10, s.bond.cs *= 10;
    s.implicit_damping = true;
    s.damping_rtol = 1e-12;
    s.damping_frozen_angle = angle;
    World w(MPI_COMM_SELF, mesh, s, {-1, -1, -1}, {1, 1, 1});
    FractureSolver& f = w.solver;
    const int spin_steps = 3000, steps = 4000;  // 5e-5 rad a step: the frozen orientations lag
    const Vec3 c{1.5 * a, 0.5 * a, 0.5 * a};
    f.setup();
    // A rigid spin about z (no dashpot sees it); after 0.15 rad, a stretching away from the centre,
    // which the dashpots damp with the bar turned from where it started.
    const double omega = 0.2 / (steps * f.dt());
    for (std::size_t e = 0; e < f.block().size(); ++e)
      f.set_velocity(e, cross(Vec3{0, 0, omega}, f.block().x0[e] - c), {0, 0, omega});
    f.setup();
    for (int k = 0; k < steps; ++k) {
      if (k == spin_steps)
        for (std::size_t e = 0; e < f.block().size(); ++e)
          f.set_velocity(e, f.v()[e] + (f.x()[e] - c) * (stretch / (3 * a)), f.w()[e]);
      f.step();
    }
    if (angle < 1) {  // the unstable run breaks it
      EXPECT_EQ(f.broken_count(), 0) << "angle " << angle;
    }
    return f.v();
  };
  const std::vector<Vec3> exact = run(0), frozen = run(1e-4), capped = run(10), undamped = run(0, false);
  double d_frozen = 0, d_capped = 0, damped = 0;
  for (std::size_t e = 0; e < exact.size(); ++e) {
    d_frozen = std::max(d_frozen, norm(frozen[e] - exact[e])), d_capped = std::max(d_capped, norm(capped[e] - exact[e]));
    damped = std::max(damped, norm(undamped[e] - exact[e]));
  }
  std::printf("largest velocity difference from angle 0: angle 1e-4 %.3g m/s, setting 10 rad (capped) %.3g m/s; "
              "what the dashpots did %.3g m/s\n", d_frozen, d_capped, damped);
  // Each solve's matrix is off by rotations of at most twice the angle: its change errs by at most
  // about that fraction, and the changes together are what the dashpots did.
  EXPECT_LT(d_frozen, 10 * 1e-4 * damped);
  // A setting of 10 rad would leave the matrix at the start's orientations, 0.15 to 0.2 rad behind:
  // no longer the theta method's, it goes unstable here (the bar breaks at 1e8 m/s; checked with the
  // cap taken out). Each element's cap, a tenth of its stiffest mode's margin (B9b), keeps it close.
  EXPECT_LT(d_capped, 1e-3 * damped);
}

}  // namespace
}  // namespace tessera
