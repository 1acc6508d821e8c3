// SPDX-License-Identifier: MIT
// Plane (2D) mode of the DEM (docs/theory.md T15): bodies are discs of a stated thickness moving in
// one plane and turning about its normal.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "support/dem_fixture.hpp"
#include "support/scene_runs.hpp"

namespace tessera::test {
namespace {

// A body rolling without slip down a slope of angle theta accelerates at g sin(theta) / (1 + I/(m R^2)):
// 2/3 g sin(theta) for a disc (I = m R^2 / 2), 5/7 for a sphere (I = 2/5 m R^2). Gravity is tilted
// instead of the floor. Returns the measured acceleration, checks the plane constraint.
double rolling_acceleration(bool plane, double theta, double& mass) {
  const Material sand = make_material("sand", 2500), wall = make_material("wall", 2500);
  ContactModel model(LawKind::linear_spring_dashpot, {sand, wall});
  const double R = 1e-3, kn = 1e4;
  const PairParams pair = ContactModel::linear_pair(kn, 2.0 / 7.0 * kn, 0.5, 0.8);  // mu > tan(theta)/3
  model.set_pair(0, 0, pair);
  model.set_pair(0, 1, pair);
  Walls walls;
  walls.add_plane({0, 0, 0}, {0, 0, 1}, 1);
  DemSettings s;
  const double g = 9.81;
  s.gravity = {g * std::sin(theta), 0, -g * std::cos(theta)};
  s.time_step = 2e-6;
  s.skin = 0.1 * R;
  if (plane) {
    s.plane_normal = 1;
    s.plane_thickness = 0.6e-3;
  }
  DemRig rig(MPI_COMM_SELF, {-0.5, -0.01, -R}, {0.5, 0.01, 0.02}, model, walls, s);
  rig.dem->add_sphere(1, 0, R, {0, 0.003, R * (1 - 1e-6)}, {}, {0, 0, 0});
  rig.dem->setup();
  const auto& p = rig.dem->particles();
  mass = p.mass[0];
  // Let the contact settle, then time the acceleration over 0.05 s.
  for (int i = 0; i < 5000; ++i) rig.dem->step();
  const double v1 = p.v[0], t1 = rig.dem->time();
  for (int i = 0; i < 25000; ++i) rig.dem->step();
  const double v2 = p.v[0], t2 = rig.dem->time();
  if (plane) {
    // In the plane (y = middle of the domain = 0, not the 0.003 it was given), no motion out of it.
    EXPECT_EQ(p.x[1], 0.0);
    EXPECT_EQ(p.v[1], 0.0);
    EXPECT_EQ(p.omega[0], 0.0);
    EXPECT_EQ(p.omega[2], 0.0);
    // The disc's orientation (its turns folded into q by complete_step) is a rotation about y by the distance
    // rolled over R: rolling without slip, up to the tangential spring's and the overlap's
    // share (about 1e-5 rad here).
    rig.dem->complete_step();
    const double turned = 2 * std::atan2(p.q[2], p.q[0]);
    std::printf("disc turned %.6f rad, rolled %.6f radii\n", turned, p.x[0] / R);
    EXPECT_NEAR(turned, p.x[0] / R, 1e-4);
    EXPECT_EQ(p.q[1], 0.0);
    EXPECT_EQ(p.q[3], 0.0);
  }
  return (v2 - v1) / (t2 - t1);
}

}  // namespace

TEST(PlaneMode, DiscRollsDownASlopeAtTwoThirdsGSinTheta) {
  const double theta = 20 * std::numbers::pi / 180, g = 9.81, R = 1e-3;
  double m_disc = 0, m_sphere = 0;
  const double a_disc = rolling_acceleration(true, theta, m_disc);
  const double a_sphere = rolling_acceleration(false, theta, m_sphere);
  if (world_rank() == 0)
    std::printf("rolling down 20 deg: disc %.6f (2/3 g sin = %.6f), sphere %.6f (5/7 g sin = %.6f) m/s^2\n", a_disc,
                2.0 / 3.0 * g * std::sin(theta), a_sphere, 5.0 / 7.0 * g * std::sin(theta));
  // The tangential spring oscillates about the rolling state; 0.05 s averages it to 1e-3.
  EXPECT_NEAR(a_disc / (2.0 / 3.0 * g * std::sin(theta)), 1.0, 1e-3);
  EXPECT_NEAR(a_sphere / (5.0 / 7.0 * g * std::sin(theta)), 1.0, 1e-3);
  EXPECT_DOUBLE_EQ(m_disc, 2500 * std::numbers::pi * R * R * 0.6e-3);
}

// A plane deposition (discs in a 2D box, split along x on 2 ranks and along x and z on 4) is bitwise
// the one-rank run, and every disc stays in the plane.
TEST(PlaneMode, DepositionIsRankCountIndependentAndStaysInThePlane) {
  const char* yaml = R"(
scene: deposition
domain: {box_min: [0, 0, 0], box_max: [12 mm, 0.6 mm, 16 mm]}
solid:
  gravity: [0, 0, -98.1]
  plane: {normal: y, thickness: 0.6 mm}
  neighbor_skin: 0.1 mm
  steps_per_contact: 20
  materials: {sand: {density: 2480}, wall: {density: 2480}}
  contact:
    law: hooke
    pairs:
      - {materials: [sand, sand], normal_stiffness: 2000, tangential_stiffness: 571.4, normal_damping_rate: 5e4, tangential_damping_rate: 2.5e4, friction: 0.4}
      - {materials: [sand, wall], normal_stiffness: 2000, tangential_stiffness: 571.4, normal_damping_rate: 5e4, tangential_damping_rate: 2.5e4, friction: 0.4}
  walls:
    - {type: box, min: [0, -1, 0], max: [12 mm, 1, 16 mm], material: wall}
deposition:
  material: sand
  diameter: 0.6 mm
  diameter_spread: 0.05
  lattice_spacing: 0.7 mm
  jitter: 0.03 mm
  seed: 11
  region_min: [0, 0, 0]
  region_max: [12 mm, 0.6 mm, 16 mm]
  settled_kinetic_energy: 1e-30 J
run: {end_time: 0.02 s}
)";
  const auto one = run_scene_on(1, yaml, {}, "plane_dep_1");
  // Progress lines come at wall-clock moments and must not change a bit: the 2-rank run has one at
  // every poll, the others (quick runs) none.
  const auto two =
      run_scene_on(2, yaml, {"domain.process_grid=[2,1,1]", "output.progress_interval=1e-9"}, "plane_dep_2");
  const auto four = run_scene_on(4, yaml, {"domain.process_grid=[2,1,2]"}, "plane_dep_4");
  if (world_rank() == 0) {
    ASSERT_GT(one.size(), 300u);
    EXPECT_EQ(count_differences(one, two, "2 ranks (2x1x1)"), 0);
    EXPECT_EQ(count_differences(one, four, "4 ranks (2x1x2)"), 0);
    // Packed state (ParticleStore::pack): id, material, shape, radius, mass, inertia, x[3], v[3],
    // omega[3], ...: y at the plane, no velocity along y, spin about y only; disc mass and inertia.
    double z_max = 0, r_min = 1, r_max = 0;
    for (const auto& [id, s] : one) {
      const double r = s[3];
      EXPECT_EQ(s[7], 0.3e-3) << id;
      EXPECT_EQ(s[10], 0.0) << id;
      EXPECT_EQ(s[12], 0.0) << id;
      EXPECT_EQ(s[14], 0.0) << id;
      EXPECT_DOUBLE_EQ(s[4], 2480 * std::numbers::pi * r * r * 0.6e-3);
      EXPECT_DOUBLE_EQ(s[5], 0.5 * s[4] * r * r);
      z_max = std::max(z_max, s[8]);
      r_min = std::min(r_min, r), r_max = std::max(r_max, r);
    }
    EXPECT_LT(z_max, 15e-3);  // the discs have fallen
    // diameter_spread 0.05: radii uniform in 0.3 mm (1 +- 0.05), spanning most of it.
    EXPECT_GE(r_min, 0.285e-3);
    EXPECT_LE(r_max, 0.315e-3);
    EXPECT_GT(r_max - r_min, 0.025e-3);
  }
}

}  // namespace tessera::test
