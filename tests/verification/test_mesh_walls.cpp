// SPDX-License-Identifier: MIT
// Triangle-mesh walls (T14) in the DEM:
//  - a sphere rolling and sliding over a flat mesh, across shared edges and vertices, moves as on
//    the plane it tiles (one contact at a time, the tangential spring kept across edges);
//  - a plate driven about a pivot by a constant moment turns as theta = w0 t + M t^2 / (2 I);
//  - a plate moving up at constant speed carries a resting sphere, and feels its weight.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "support/dem_fixture.hpp"

namespace tessera::test {
namespace {

// Square [0, L]^2 at z = 0 as an n x n grid of squares, each cut into two triangles along
// alternating diagonals (so that edges and vertices of both kinds are crossed).
MeshWall floor_mesh(double L, int n, int material) {
  MeshWall m;
  m.material = material;
  m.key = "floor";
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.local.push_back({L * i / n, L * j / n, 0});
  auto id = [&](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if ((i + j) % 2) {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        m.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      }
  return m;
}

TEST(MeshWalls, SphereCrossingEdgesMovesAsOnThePlane) {
  const double R = 1e-3, L = 0.02;
  const Material sand = make_material("sand", 2650);
  ContactModel model(LawKind::linear_spring_dashpot, {sand});
  model.set_pair(0, 0, ContactModel::linear_pair(1e4, 1e4, 0.5, 0.3));
  DemSettings s;
  s.skin = 0.2 * R;
  auto run = [&](bool mesh, std::vector<Vec3>& track) {
    Walls walls;
    if (mesh)
      walls.add_mesh(floor_mesh(L, 8, 0));
    else
      walls.add_plane({0, 0, 0}, {0, 0, 1}, 0);
    DemRig rig(MPI_COMM_SELF, {0, 0, -L}, {L, L, L}, model, walls, s);
    // Drops on the floor, then slides and rolls diagonally across edges and vertices.
    rig.dem->add_sphere(1, 0, R, {2e-3, 3e-3, R + 2e-5}, {0.12, 0.09, 0}, {40, -10, 5});
    rig.dem->setup();
    const auto& p = rig.dem->particles();
    for (int n = 0; n < 40000; ++n) {
      rig.dem->step();
      if (n % 1000 == 0) track.push_back(p.pos(0));
    }
    track.push_back(p.pos(0));
    return rig.dem->dt() * 40000;
  };
  std::vector<Vec3> on_plane, on_mesh;
  run(false, on_plane);
  const double t = run(true, on_mesh);
  double worst = 0;
  for (std::size_t k = 0; k < on_plane.size(); ++k) worst = std::max(worst, norm(on_plane[k] - on_mesh[k]));
  const Vec3 travel = on_plane.back() - on_plane.front();
  std::printf("  %.3f s, travelled %.2f mm over a mesh of 2 x 64 triangles: largest gap plane/mesh %.3g m\n", t,
              1e3 * norm(travel), worst);
  EXPECT_GT(norm(travel), 3 * L / 8);  // crossed several grid squares (edges, vertices)
  EXPECT_LT(worst, 1e-12);
}

TEST(MeshWalls, PivotedPlateFollowsTheAppliedMoment) {
  // No contact, no mass: theta'' = M / I; velocity Verlet is exact for a constant acceleration.
  const Material m0 = make_material("m", 2650);
  ContactModel model(LawKind::linear_spring_dashpot, {m0});
  model.set_pair(0, 0, ContactModel::linear_pair(1e4, 1e4, 0.5, 0.3));
  Walls walls;
  MeshWall plate = floor_mesh(0.01, 2, 0);
  plate.motion = MeshWall::Motion::pivot;
  plate.origin = {0, 0, 0};
  plate.axis = {0, 1, 0};
  plate.inertia = 2e-6;
  plate.applied_moment = 3e-5;
  plate.theta_dot = -4.0;
  walls.add_mesh(plate);
  DemSettings s;
  s.time_step = 1e-5;
  s.gravity = {0, 0, 0};
  DemRig rig(MPI_COMM_SELF, {-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05}, model, walls, s);
  rig.dem->add_sphere(1, 0, 1e-3, {0.04, 0.04, 0.04}, {});
  rig.dem->setup();
  for (int n = 0; n < 5000; ++n) rig.dem->step();
  const MeshWall& m = rig.dem->walls().meshes()[0];
  const double t = 5000 * 1e-5, alpha = 3e-5 / 2e-6;
  const double theta = -4.0 * t + 0.5 * alpha * t * t;
  std::printf("  theta %.12f (exact %.12f), theta' %.12f (exact %.12f)\n", m.theta, theta, m.theta_dot,
              -4.0 + alpha * t);
  EXPECT_NEAR(m.theta, theta, 1e-11);  // round-off of 5000 steps
  EXPECT_NEAR(m.theta_dot, -4.0 + alpha * t, 1e-10);
  // The far corner of the plate (0.01, 0.01, 0) turned about y by theta.
  const Vec3 corner = m.nodes.back();
  EXPECT_NEAR(corner.x, 0.01 * std::cos(theta), 1e-15);
  EXPECT_NEAR(corner.z, -0.01 * std::sin(theta), 1e-15);
}

TEST(MeshWalls, RisingPlateCarriesASphereAndFeelsItsWeight) {
  const double R = 1e-3;
  const Material sand = make_material("sand", 2650);
  ContactModel model(LawKind::linear_spring_dashpot, {sand});
  model.set_pair(0, 0, ContactModel::linear_pair(1e4, 1e4, 0.3, 0.5));
  Walls walls;
  MeshWall plate = floor_mesh(0.01, 4, 0);
  plate.motion = MeshWall::Motion::prescribed;
  plate.velocity = {0, 0, 0.05};
  walls.add_mesh(plate);
  DemSettings s;
  s.skin = 0.2 * R;
  DemRig rig(MPI_COMM_SELF, {0, 0, -0.01}, {0.01, 0.01, 0.05}, model, walls, s);
  rig.dem->add_sphere(1, 0, R, {0.004, 0.005, R}, {});
  rig.dem->setup();
  const int steps = static_cast<int>(0.1 / rig.dem->dt());
  for (int n = 0; n < steps; ++n) rig.dem->step();
  rig.dem->sum_mesh_loads();  // a prescribed mesh's load is completed when reported
  const auto& p = rig.dem->particles();
  const MeshWall& m = rig.dem->walls().meshes()[0];
  const double weight = p.mass[0] * 9.81;
  std::printf("  after 0.1 s: sphere vz %.6f m/s (plate 0.05), load on plate %.6f weights, list builds %zu\n", p.v[2],
              -m.force.z / weight, rig.dem->list_builds());
  EXPECT_NEAR(p.v[2], 0.05, 1e-4);
  EXPECT_NEAR(-m.force.z / weight, 1.0, 1e-3);
  EXPECT_NEAR(p.x[2] - m.nodes[0].z, R, 0.01 * R);  // resting on it (static overlap m g / k)
  EXPECT_GT(rig.dem->list_builds(), 3u);            // the moving plate triggered rebuilds
}

TEST(MeshWalls, ReadFromStlAndGmshThroughTheCaseFile) {
  const std::string data = std::string(TESSERA_SOURCE_DIR) + "/tests/data/";
  const std::string text = R"(
solid:
  materials: {sand: {density: 2650}, wall: {density: 2650}}
  contact:
    law: hooke
    pairs: [{materials: [sand, wall], normal_stiffness: 1e4, restitution: 0.5, friction: 0.5}]
  walls:
    - {type: mesh, file: valley.stl, scale: 1e-3, material: wall, motion: {type: fixed}}
    - type: mesh
      file: grain_spheroid.msh
      scale: 1e-3
      material: wall
      motion: {type: prescribed, velocity: [0, 0, 1 mm/s], angular_velocity: [0, 0, 2 rad/s], centre: [1 mm, 0, 0]}
)";
  Config c = Config::parse(text);
  const ConfigNode solid = c.root().section("solid");
  ContactModel model(solid);
  Walls walls(solid, model, data);
  ASSERT_EQ(walls.meshes().size(), 2u);
  EXPECT_EQ(walls.meshes()[0].triangles.size(), 4u);
  EXPECT_NEAR(walls.meshes()[0].nodes[1].x, 3e-3, 1e-15);  // scaled from mm
  EXPECT_GT(walls.meshes()[1].triangles.size(), 50u);      // the spheroid's surface triangles
  EXPECT_EQ(walls.meshes()[1].motion, MeshWall::Motion::prescribed);
  EXPECT_NEAR(walls.meshes()[1].omega.z, 2.0, 1e-15);
  // A file that is not a surface mesh is refused, naming the key.
  Config bad = Config::parse(std::string(text).replace(text.find("valley.stl"), 10, "valley.obj"));
  const ConfigNode bs = bad.root().section("solid");
  try {
    Walls w(bs, ContactModel(bs), data);
    FAIL() << "accepted a .obj mesh";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("solid.walls"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tessera::test
