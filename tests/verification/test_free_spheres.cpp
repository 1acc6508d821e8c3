// SPDX-License-Identifier: MIT
// Free spheres (docs/theory.md T17): a body far larger than the grains, kept whole on every rank.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "support/dem_fixture.hpp"
#include "support/scene_runs.hpp"

namespace tessera::test {
namespace {

ContactModel two_material_model(double kn, double mu) {
  const Material sand = make_material("sand", 2500), ball = make_material("ball", 1000);
  ContactModel model(LawKind::linear_spring_dashpot, {sand, ball});
  const PairParams pair = ContactModel::linear_pair(kn, 2.0 / 7.0 * kn, 0.5, mu);
  model.set_pair(0, 0, pair);
  model.set_pair(0, 1, pair);
  model.set_pair(1, 1, pair);
  return model;
}

}  // namespace

// A free disc (plane mode) rolling without slip down a 20 deg slope accelerates at 2/3 g sin(theta),
// as a grain disc does (PlaneMode test): its wall contacts, masses and half-kicks are the grains'.
// Its mass is rho pi R^2 t and it stays in the plane.
TEST(FreeSphere, DiscRollsDownASlopeAtTwoThirdsGSinTheta) {
  ContactModel model = two_material_model(1e5, 0.8);
  Walls walls;
  walls.add_plane({0, 0, 0}, {0, 0, 1}, 0);
  DemSettings s;
  const double g = 9.81, theta = 20 * std::numbers::pi / 180, R = 0.0215, t = 1.9e-3;
  s.gravity = {g * std::sin(theta), 0, -g * std::cos(theta)};
  s.time_step = 2e-6;
  s.skin = 1e-4;
  s.plane_normal = 1;
  s.plane_thickness = t;
  DemRig rig(MPI_COMM_SELF, {-1, -0.01, -0.01}, {1, 0.01, 0.1}, model, walls, s);
  rig.dem->add_sphere(1, 0, 1e-3, {-0.9, 0, 0.05}, {});  // a grain elsewhere: a scene has bodies
  rig.dem->add_free_sphere("ball", 1, R, {0, 0.004, R * (1 - 1e-6)}, {});
  rig.dem->setup();
  const FreeSphere& b = rig.dem->free_spheres()[0];
  for (int i = 0; i < 5000; ++i) rig.dem->step();
  const double v1 = b.v.x, t1 = rig.dem->time();
  for (int i = 0; i < 25000; ++i) rig.dem->step();
  const double a = (b.v.x - v1) / (rig.dem->time() - t1);
  if (world_rank() == 0)
    std::printf("free disc rolling down 20 deg: %.6f m/s^2 (2/3 g sin = %.6f)\n", a, 2.0 / 3.0 * g * std::sin(theta));
  EXPECT_NEAR(a / (2.0 / 3.0 * g * std::sin(theta)), 1.0, 1e-3);
  EXPECT_DOUBLE_EQ(b.mass, 1000 * std::numbers::pi * R * R * t);
  EXPECT_EQ(b.x.y, 0.0);
  EXPECT_EQ(b.v.y, 0.0);
  EXPECT_EQ(b.omega.x, 0.0);
  EXPECT_EQ(b.omega.z, 0.0);
}

// A grain fired at a free sphere (3D, no gravity, off-centre so that friction spins both): the
// total linear momentum is conserved to round-off through the contact, and the grain bounces back
// at the restitution's speed along the line of centres within the law's accuracy for m* != m.
TEST(FreeSphere, GrainImpactConservesMomentum) {
  ContactModel model = two_material_model(1e5, 0.3);
  Walls walls;
  DemSettings s;
  s.gravity = {0, 0, 0};
  s.time_step = 2e-7;
  s.skin = 1e-4;
  DemRig rig(MPI_COMM_SELF, {-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1}, model, walls, s);
  const double r = 1e-3, R = 0.02;
  rig.dem->add_sphere(1, 0, r, {-R - r - 2e-4, 0, 0.3 * R}, {2.0, 0, 0});
  rig.dem->add_free_sphere("ball", 1, R, {0, 0, 0}, {});
  rig.dem->setup();
  const auto& p = rig.dem->particles();
  const FreeSphere& b = rig.dem->free_spheres()[0];
  auto momentum = [&] { return Vec3{p.v[0], p.v[1], p.v[2]} * p.mass[0] + b.v * b.mass; };
  const Vec3 before = momentum();
  double max_force = 0;
  for (int i = 0; i < 3000; ++i) {
    rig.dem->step();
    max_force = std::max(max_force, norm(b.force));
  }
  const Vec3 after = momentum();
  if (world_rank() == 0)
    std::printf("grain on free sphere: momentum %.3e -> %.3e kg m/s, peak force %.3g N, ball v %.3e m/s\n",
                norm(before), norm(after), max_force, norm(b.v));
  EXPECT_GT(max_force, 0.1);         // they did collide
  EXPECT_NEAR(b.force.x, 0.0, 0.0);  // and separated
  EXPECT_LT(norm(after - before), 1e-15 * norm(before) + 1e-20);
  EXPECT_GT(norm(b.omega), 0.0);  // the tangential force turned the ball
  EXPECT_LT(p.v[0], 0.0);         // the grain came back
}

}  // namespace tessera::test

namespace tessera::test {

// The bunker-shot pipeline at toy size, its rank-count independence and its restart: a plane bed of
// about 900 discs of 1 mm, a 16 mm ball dropped on it, then a shot with a 100 mm shaft. The shot
// from the same bed file on 1, 2 (2x1x1) and 4 (4x1x1) ranks gives the same quantities to the last
// bit (the ball's load is summed in contact-key order on every rank, the club's too), and so does a
// shot stopped at 4 ms and restarted from its checkpoint.
TEST(BunkerShot, ToyShotIsRankCountIndependent) {
  const std::string solid = R"(
solid:
  gravity: [0, 0, -98.1]
  plane: {normal: y, thickness: 1 mm}
  neighbor_skin: 0.1 mm
  steps_per_contact: 20
  impact_velocity: 5 m/s
  materials: {sand: {density: 2480}, wall: {density: 2480}, ball: {density: 1000}, club: {density: 7800}}
  contact:
    law: hooke
    pairs:
      - {materials: [sand, sand], normal_stiffness: 1e5, tangential_stiffness: 2.857e4, restitution: 0.3, friction: 0.25}
      - {materials: [sand, wall], normal_stiffness: 1e5, tangential_stiffness: 2.857e4, restitution: 0.3, friction: 0.17}
      - {materials: [ball, sand], normal_stiffness: 1e5, tangential_stiffness: 2.857e4, restitution: 0.3, friction: 0.2}
      - {materials: [ball, wall], normal_stiffness: 1e5, tangential_stiffness: 2.857e4, restitution: 0.3, friction: 0.2}
      - {materials: [club, sand], normal_stiffness: 1e5, tangential_stiffness: 2.857e4, restitution: 0.3, friction: 0.2}
      - {materials: [club, ball], normal_stiffness: 1e5, tangential_stiffness: 2.857e4, restitution: 0.3, friction: 0.2}
  walls:
    - {type: box, min: [0, -1, 0], max: [60 mm, 1, 50 mm], material: wall}
)";
  const std::string domain = "domain: {box_min: [0, 0, 0], box_max: [60 mm, 1 mm, 50 mm]}\n";
  const std::string bed = "scene: deposition\n" + domain + solid + R"(
deposition:
  material: sand
  diameter: 1 mm
  diameter_spread: 0.05
  lattice_spacing: 1.15 mm
  jitter: 0.03 mm
  seed: 5
  region_min: [0, 0, 0]
  region_max: [60 mm, 1 mm, 20 mm]
  settled_kinetic_energy: 1e-9 J
  min_time: 0.02 s
run: {end_time: 0.2 s, check_interval: 2 ms}
)";
  const std::string ball_line =
      "  free_spheres:\n    - {key: ball, material: ball, diameter: 16 mm, position: [30 mm, 0, 30 mm]}\n";
  const std::string drop =
      "scene: bed\n" + domain + solid + ball_line +
      "bed: {file: toy_bunker_bed/checkpoint.h5, settled_kinetic_energy: 1e-8 J, min_time: 10 ms}\n"
      "run: {end_time: 0.2 s, check_interval: 2 ms}\n";
  const std::string shot = "scene: bunker_shot\n" + domain + solid + ball_line + R"(
bed: {file: toy_bunker_ball/checkpoint.h5}
club: {loft_deg: 58, bounce_deg: 10, shot_depth: 1 mm, shaft_length: 100 mm, angular_velocity: 50 rad/s,
       mass_per_depth: 4.0, moment_of_inertia_per_depth: 0.05, material: club}
run: {end_time: 8 ms, check_interval: 0.5 ms}
)";
  run_case_on(2, bed, {}, "toy_bunker_bed");
  // The drop ends when the ball and bed are at rest (bed.settled_kinetic_energy), well before 0.2 s.
  const auto dropped = run_case_on(2, drop, {}, "toy_bunker_ball");
  const auto one = run_case_on(1, shot, {}, "toy_bunker_shot_1");
  const auto two = run_case_on(2, shot, {"domain.process_grid=[2,1,1]"}, "toy_bunker_shot_2");
  const auto four = run_case_on(4, shot, {"domain.process_grid=[4,1,1]"}, "toy_bunker_shot_4");
  // Restart: 4 ms, a checkpoint, then on to 8 ms (the club, the ball, the impulse and the release
  // so far come back from the checkpoint).
  run_case_on(2, shot, {"domain.process_grid=[2,1,1]", "run.end_time=4ms"}, "toy_bunker_shot_r");
  const auto resumed = run_case_on(2, shot, {"domain.process_grid=[2,1,1]"}, "toy_bunker_shot_r",
                                   std::string("toy_bunker_shot_r/checkpoint.h5"));
  if (world_rank() != 0) return;
  std::printf("toy drop: settled at %.4g s\n", dropped["quantities"]["settle_time"].get<double>());
  EXPECT_TRUE(dropped["quantities"]["settled"].get<bool>());
  EXPECT_LT(dropped["time"].get<double>(), 0.19);
  EXPECT_LT(dropped["quantities"]["kinetic_energy"].get<double>(), 1e-8);
  const auto& q = one["quantities"];
  std::printf("toy shot: release %.3f deg at %.4f m/s (t = %.4g s), impulse %.4g, club loses %.3f rad/s\n",
              q["release_angle_deg"].get<double>(), q["release_speed_mps"].get<double>(),
              q["release_time"].get<double>(), q["club_upward_impulse"].get<double>(),
              q["club_angular_velocity_loss"].get<double>());
  EXPECT_GT(q["release_speed_mps"].get<double>(), 0.5);  // the club moved the ball
  EXPECT_GT(q["club_angular_velocity_loss"].get<double>(), 0.0);
  for (const char* k : {"release_angle_deg", "release_speed_mps", "release_time", "club_upward_impulse",
                        "club_angular_velocity_loss"}) {
    EXPECT_EQ(q[k].get<double>(), two["quantities"][k].get<double>()) << k << " on 2 ranks";
    EXPECT_EQ(q[k].get<double>(), four["quantities"][k].get<double>()) << k << " on 4 ranks";
  }
  EXPECT_EQ(one["free_spheres"][0]["position"], four["free_spheres"][0]["position"]);
  for (const char* k : {"release_angle_deg", "release_speed_mps", "release_time", "club_upward_impulse",
                        "club_angular_velocity_loss", "club_start_angle_deg"})
    EXPECT_EQ(two["quantities"][k].get<double>(), resumed["quantities"][k].get<double>()) << k << " after a restart";
  EXPECT_EQ(two["free_spheres"][0]["velocity"], resumed["free_spheres"][0]["velocity"]);
}

}  // namespace tessera::test
