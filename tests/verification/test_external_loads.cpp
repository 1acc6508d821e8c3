// SPDX-License-Identifier: MIT
// External loads on bodies (ParticleStore::f_ext, t_ext; the seam the fluid force and the blast's
// borehole pressure use) and DemSolver::advance(dt, substeps).
//
// References: under a constant force F and torque T, with no contacts and no gravity, velocity
// Verlet is exact (a constant acceleration has no truncation error), so
//   x(t) = x0 + v0 t + F t^2 / (2 m),  v(t) = v0 + F t / m,  w(t) = w0 + T t / I  (sphere, I = 2/5 m r^2);
// for a rigid body of any shape the torque changes the world angular momentum by exactly T t
// (the free rotation between the half-kicks conserves it, T9). Tolerances: round-off over a few
// thousand steps (1e-10 relative). Half-step velocities left at the end of advance() would be off
// by F dt / (2 m), 1e-4 relative here: the tests would see it.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <numbers>

#include "solid/shape.hpp"
#include "support/dem_fixture.hpp"

namespace tessera::test {
namespace {

Vec3 force_of(std::int64_t id) { return {1e-5 * (1 + id % 3), -2e-5 * (id % 2), 0.5e-5}; }
Vec3 torque_of(std::int64_t id) { return {0, 3e-10 * (1 + id % 2), -1e-10}; }

TEST(ExternalLoads, ConstantForceAndTorqueAreIntegratedExactlyAcrossRanks) {
  // 8 spheres far apart fly along x through a domain split into slabs along x (1 to 4 ranks):
  // each crosses sub-domain boundaries, and its load must travel with it.
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const double R = 1e-3, L = 0.8;
  const Material sand = make_material("sand", 2650);
  ContactModel model(LawKind::linear_spring_dashpot, {sand});
  model.set_pair(0, 0, ContactModel::linear_pair(1e3, 1e3, 0.5, 0.3));
  DemSettings s;
  s.gravity = {0, 0, 0};
  s.time_step = 1e-4;
  s.skin = 0.5 * R;
  DemRig rig(MPI_COMM_WORLD, {0, 0, 0}, {L, 0.1, 0.1}, model, Walls{}, s, {size, 1, 1});
  const double m = sand.density * 4.0 / 3.0 * std::numbers::pi * R * R * R, inertia = 0.4 * m * R * R;
  struct Start {
    Vec3 x, v, w;
  };
  std::vector<Start> start;
  for (int id = 0; id < 8; ++id) {
    const Vec3 x{0.02 + 0.005 * id, 0.01 + 0.01 * id, 0.05}, v{10.0 + id, 0.01, -0.02}, w{0, 5.0 * id, 1.0};
    start.push_back({x, v, w});
    rig.dem->add_sphere(id, 0, R, x, v, w);
  }
  rig.dem->setup();
  auto& p = rig.dem->particles();
  for (std::size_t i = 0; i < p.owned; ++i) {
    force_of(p.id[i]).store(&p.f_ext[3 * i]);
    torque_of(p.id[i]).store(&p.t_ext[3 * i]);
  }
  rig.dem->use_external_loads(true);
  // Sub-cycled as a coupled flow step would: 40 flow steps of 5 DEM steps, then 3 of 7 smaller ones.
  for (int n = 0; n < 40; ++n) rig.dem->advance(1e-4, 5);
  for (int n = 0; n < 3; ++n) rig.dem->advance(0.5e-4, 7);
  const double t = 40 * 5 * 1e-4 + 3 * 7 * 0.5e-4;
  EXPECT_NEAR(rig.dem->time(), t, 1e-15);
  long found = 0;
  for (std::size_t i = 0; i < p.owned; ++i, ++found) {
    const auto id = p.id[i];
    const Start& s0 = start[static_cast<std::size_t>(id)];
    const Vec3 a = force_of(id) / m, alpha = torque_of(id) / inertia;
    const Vec3 x = s0.x + s0.v * t + a * (0.5 * t * t), v = s0.v + a * t, w = s0.w + alpha * t;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(p.x[3 * i + k], x[k], 1e-10 * L) << "body " << id << " x" << k;
      EXPECT_NEAR(p.v[3 * i + k], v[k], 1e-10 * norm(v)) << "body " << id << " v" << k;
      EXPECT_NEAR(p.omega[3 * i + k], w[k], 1e-10 * norm(w)) << "body " << id << " w" << k;
    }
  }
  long total = found, migrations = static_cast<long>(rig.dem->migrations());
  MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &migrations, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, 8);
  // Bodies move 0.21 to 0.36 m from x = 0.02 to 0.055 m: on 4 slabs of 0.2 m each changes owner.
  if (size == 4) {
    EXPECT_GE(migrations, 8);
  }

  // Off: the loads are kept but not read; the bodies fly at constant velocity.
  rig.dem->use_external_loads(false);
  rig.dem->advance(1e-4, 10);
  for (std::size_t i = 0; i < p.owned; ++i) {
    const auto id = p.id[i];
    const Vec3 v = start[static_cast<std::size_t>(id)].v + force_of(id) / m * t;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(p.v[3 * i + k], v[k], 1e-10 * norm(v)) << "body " << id << " v" << k;
  }
}

TEST(ExternalLoads, TorqueOnAnAsymmetricBodyChangesItsAngularMomentumByTt) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  ellipsoid_mesh({3e-3, 2e-3, 1e-3}, 8, 16, nodes, tets);
  const Material mat = make_material("m", 2650);
  ContactModel model(LawKind::linear_spring_dashpot, {mat});
  model.set_pair(0, 0, ContactModel::linear_pair(1e4, 1e4, 0.5, 0.5));
  DemSettings s;
  s.gravity = {0, 0, 0};
  s.time_step = 1e-4;
  DemRig rig(MPI_COMM_SELF, {-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1}, model, Walls{}, s);
  rig.dem->set_shapes({ShapeTemplate::from_mesh("e", nodes, tets, 20, 0.5e-3)});
  const Quaternion q0{0.9, 0.2, -0.3, 0.25};
  rig.dem->add_body(1, 0, 1, {0, 0, 0}, q0, {0, 0, 0}, {3.0, -1.0, 2.0});
  rig.dem->setup();
  auto& p = rig.dem->particles();
  const ShapeTemplate& shape = rig.dem->shapes()[0];
  const Vec3 inertia = shape.inertia_per_density * (p.mass[0] / shape.volume);
  auto world_momentum = [&] {
    const Quaternion q{p.q[0], p.q[1], p.q[2], p.q[3]};
    const Vec3 wb = q.unrotate(p.ang(0));
    return q.rotate({inertia.x * wb.x, inertia.y * wb.y, inertia.z * wb.z});
  };
  const Vec3 l0 = world_momentum(), torque{2e-9, -1e-9, 3e-9}, force{1e-6, 0, 0};
  torque.store(&p.t_ext[0]);
  force.store(&p.f_ext[0]);
  rig.dem->use_external_loads(true);
  for (int n = 0; n < 100; ++n) rig.dem->advance(1e-4, 20);
  const double t = 0.2;
  const Vec3 expected = l0 + torque * t, got = world_momentum();
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], expected[k], 1e-10 * norm(expected)) << k;
  // The torque did matter: |T t| is comparable to |L0|.
  EXPECT_GT(norm(torque * t), 0.1 * norm(l0));
  EXPECT_NEAR(p.x[0], 0.5 * force.x / p.mass[0] * t * t, 1e-10 * 0.5 * force.x / p.mass[0] * t * t);
}

}  // namespace
}  // namespace tessera::test
