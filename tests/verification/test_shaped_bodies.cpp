// SPDX-License-Identifier: MIT
// Bodies made of tetrahedra with contact spheres (shape templates, T13) in the DEM:
//  - a template of one central sphere moves like the plain sphere of the same size;
//  - a torque-free asymmetric body keeps its energy and world angular momentum;
//  - a spheroid dropped on a plane gains no energy whatever its orientation, and tip down (one
//    contact sphere on the axis) rebounds with the law's restitution;
//  - a spheroid released tilted comes to rest lying flat, the plane carrying its weight.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "support/dem_fixture.hpp"

namespace tessera::test {
namespace {

constexpr double kA = 0.635e-3, kB = 0.26e-3, kRho = 1e-4;  // the seed's grain, 75 spheres of 0.1 mm

ShapeTemplate seed_grain() {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  ellipsoid_mesh({kA, kB, kB}, 5, 9, nodes, tets);
  return ShapeTemplate::from_mesh("grain", nodes, tets, 75, kRho);
}

Quaternion axis_angle(const Vec3& axis, double angle) {
  const Vec3 u = axis / norm(axis);
  return {std::cos(0.5 * angle), u.x * std::sin(0.5 * angle), u.y * std::sin(0.5 * angle), u.z * std::sin(0.5 * angle)};
}

// Principal moments of body i (from its template and mass).
Vec3 body_inertia(const DemSolver& dem, std::size_t i) {
  const auto& p = dem.particles();
  const ShapeTemplate& t = dem.shapes()[p.shape[i] - 1];
  return t.inertia_per_density * (p.mass[i] / t.volume);
}

Quaternion orientation(const ParticleStore& p, std::size_t i) {
  return {p.q[4 * i], p.q[4 * i + 1], p.q[4 * i + 2], p.q[4 * i + 3]};
}

TEST(ShapedBodies, OneCentralSphereTemplateMovesLikeTheSphere) {
  // 64 spheres fall with spin into a box with friction; the same run with each sphere a body of a
  // one-sphere template (equal principal moments: it rotates by the sphere update). The element
  // path (list, kernel, walls, force reduction) must then give bitwise the same trajectories.
  const double R = 4e-4, L = 6e-3;
  const Material sand = make_material("sand", 2048);  // a power of 2: m / rho * rho == m exactly
  ContactModel model(LawKind::linear_spring_dashpot, {sand});
  model.set_pair(0, 0, ContactModel::linear_pair(2000, 2000, 0.5, 0.5));
  Walls walls;
  walls.add_box_inside({0, 0, 0}, {L, L, L}, 0);
  DemSettings s;
  s.skin = 0.2 * R;
  ShapeTemplate ball;
  ball.name = "ball";
  ball.spheres = {{0, 0, 0}};
  ball.sphere_radius = ball.bounding_radius = R;
  // The sphere's own mass and inertia expressions (DemSolver::add_sphere), per unit density.
  const double m = sand.density * 4.0 / 3.0 * std::numbers::pi * R * R * R;
  ball.volume = m / sand.density;
  ball.inertia_per_density = Vec3{1, 1, 1} * (0.4 * m * R * R / sand.density);
  auto run = [&](bool shaped) {
    DemRig rig(MPI_COMM_SELF, {0, 0, 0}, {L, L, L}, model, walls, s);
    if (shaped) rig.dem->set_shapes({ball});
    std::int64_t id = 1;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        for (int k = 0; k < 4; ++k, ++id) {
          const Vec3 x{(i + 0.6) * 1.3e-3, (j + 0.6) * 1.3e-3, (k + 0.6) * 1.3e-3 + 0.5e-3};
          const Vec3 v{0.2 * std::sin(1.7 * id), 0.2 * std::cos(0.9 * id), -0.3};
          const Vec3 w{30 * std::sin(0.3 * id), 20 * std::cos(1.1 * id), 10.0};
          if (shaped)
            rig.dem->add_body(id, 0, 1, x, {}, v, w);
          else
            rig.dem->add_sphere(id, 0, R, x, v, w);
        }
    rig.dem->setup();
    long touching = 0;  // contacts seen, summed over samples
    for (int n = 0; n < 16000; ++n) {
      rig.dem->step();
      if (n % 100 == 0) touching += rig.dem->stats().contacts + rig.dem->stats().wall_contacts;
    }
    const auto& p = rig.dem->particles();
    std::vector<double> state;
    for (std::size_t i = 0; i < p.owned; ++i) {
      state.push_back(static_cast<double>(p.id[i]));
      for (int k = 0; k < 3; ++k) state.push_back(p.x[3 * i + k]);
      for (int k = 0; k < 3; ++k) state.push_back(p.v[3 * i + k]);
      for (int k = 0; k < 3; ++k) state.push_back(p.omega[3 * i + k]);
    }
    return std::pair{state, touching};
  };
  const auto [a, sa] = run(false);
  const auto [b, sb] = run(true);
  ASSERT_EQ(a.size(), b.size());
  double dx = 0, dv = 0, dw = 0;
  for (std::size_t k = 0; k < a.size(); k += 10) {
    ASSERT_EQ(a[k], b[k]);
    for (int c = 0; c < 3; ++c) {
      dx = std::max(dx, std::fabs(a[k + 1 + c] - b[k + 1 + c]));
      dv = std::max(dv, std::fabs(a[k + 4 + c] - b[k + 4 + c]));
      dw = std::max(dw, std::fabs(a[k + 7 + c] - b[k + 7 + c]));
    }
  }
  std::printf("  max difference: position %.3g m, velocity %.3g m/s, spin %.3g rad/s; %ld contacts sampled\n", dx, dv,
              dw, sa);
  EXPECT_GT(sa, 300);  // the bodies are in contact: the test exercises forces
  EXPECT_EQ(sa, sb);
  EXPECT_EQ(dx, 0.0);
  EXPECT_EQ(dv, 0.0);
  EXPECT_EQ(dw, 0.0);
}

TEST(ShapedBodies, TorqueFreeAsymmetricBodyConservesEnergyAndMomentum) {
  // An ellipsoid 3:2:1 spun close to its intermediate axis tumbles (Dzhanibekov); DLM splitting
  // keeps the energy error bounded and L_world to round-off.
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  ellipsoid_mesh({3e-3, 2e-3, 1e-3}, 8, 16, nodes, tets);
  const Material m = make_material("m", 2650);
  ContactModel model(LawKind::linear_spring_dashpot, {m});
  model.set_pair(0, 0, ContactModel::linear_pair(1e4, 1e4, 0.5, 0.5));
  DemSettings s;
  s.gravity = {0, 0, 0};
  s.time_step = 2e-4;
  DemRig rig(MPI_COMM_SELF, {-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1}, model, Walls{}, s);
  rig.dem->set_shapes({ShapeTemplate::from_mesh("e", nodes, tets, 20, 0.5e-3)});
  rig.dem->add_body(1, 0, 1, {0, 0, 0}, axis_angle({1, 2, 3}, 0.7), {}, {0, 0, 0});
  const auto& p = rig.dem->particles();
  // w: mostly along the body's intermediate axis (body y), a little along the others.
  const Quaternion q0 = orientation(p, 0);
  const Vec3 w0 = q0.rotate({0.1, 10.0, 0.05});
  rig.dem->particles().omega = {w0.x, w0.y, w0.z};
  rig.dem->setup();
  auto momentum = [&] {
    const Vec3 I = body_inertia(*rig.dem, 0);
    const Quaternion q = orientation(p, 0);
    const Vec3 wb = q.unrotate(p.ang(0));
    return std::pair{q.rotate({I.x * wb.x, I.y * wb.y, I.z * wb.z}),
                     0.5 * (I.x * wb.x * wb.x + I.y * wb.y * wb.y + I.z * wb.z * wb.z)};
  };
  const auto [L0, E0] = momentum();
  double e_err = 0, l_err = 0, min_wy = 1e300, q_err = 0;
  for (int n = 0; n < 100000; ++n) {
    rig.dem->step();
    if (n % 100) continue;
    const auto [L, E] = momentum();
    e_err = std::max(e_err, std::fabs(E / E0 - 1));
    l_err = std::max(l_err, norm(L - L0) / norm(L0));
    min_wy = std::min(min_wy, orientation(p, 0).unrotate(p.ang(0)).y);
    q_err = std::max(q_err, std::fabs(orientation(p, 0).norm2() - 1));
  }
  std::printf("  100000 steps (w dt = 2e-3): |dE/E| %.3g, |dL|/|L| %.3g, ||q|^2 - 1| %.3g, min w_y %.3g\n", e_err,
              l_err, q_err, min_wy);
  EXPECT_LT(min_wy, -5.0);  // it flipped
  EXPECT_LT(e_err, 1e-5);
  EXPECT_LT(l_err, 1e-9);  // round-off: w is the state, L = R I R^T w is rebuilt each half-step
  EXPECT_LT(q_err, 1e-14);
}

struct DropResult {
  double ke_in = 0, ke_out = 0, vz_out = 0;
};

DropResult drop(const Quaternion& q, double restitution, double friction) {
  const Material sand = make_material("sand", 2650);
  ContactModel model(LawKind::linear_spring_dashpot, {sand});
  const double kn = 1e4;
  model.set_pair(0, 0, ContactModel::linear_pair(kn, friction > 0 ? kn : 0.0, restitution, friction));
  Walls walls;
  walls.add_plane({0, 0, 0}, {0, 0, 1}, 0);
  const ShapeTemplate grain = seed_grain();
  const double mass = sand.density * grain.volume;
  DemSettings s;
  s.gravity = {0, 0, 0};
  s.time_step = std::numbers::pi * std::sqrt(mass / kn) / 400;
  s.skin = 0.2 * kRho;
  DemRig rig(MPI_COMM_SELF, {-2e-3, -2e-3, -1e-3}, {2e-3, 2e-3, 3e-3}, model, walls, s);
  rig.dem->set_shapes({grain});
  // Lowest point of the contact-sphere envelope just above the plane.
  double low = 1e300;
  for (const auto& c : grain.spheres) low = std::min(low, q.rotate(c).z - kRho);
  const double v0 = 0.1;
  rig.dem->add_body(1, 0, 1, {0, 0, -low + 1e-6}, q, {0, 0, -v0}, {});
  rig.dem->setup();
  const auto& p = rig.dem->particles();
  DropResult r;
  r.ke_in = rig.dem->stats().kinetic_translational + rig.dem->stats().kinetic_rotational;
  bool touched = false;
  for (int n = 0; n < 40000; ++n) {
    rig.dem->step();
    const bool now = rig.dem->stats().wall_contacts > 0;
    if (touched && !now) break;
    touched = touched || now;
  }
  EXPECT_TRUE(touched);
  const DemStats st = rig.dem->stats();
  r.ke_out = st.kinetic_translational + st.kinetic_rotational;
  r.vz_out = p.v[2] / v0;
  return r;
}

TEST(ShapedBodies, DroppedSpheroidGainsNoEnergyAndReboundsByTheLaw) {
  // Tip down: one contact sphere on the axis touches, the arm is along the normal, no torque: the
  // rebound is e v0 as for a sphere of the body's mass (T4); velocity Verlet at t_c / 400 errs by
  // ~ zeta w_n dt, below 1 %.
  const Quaternion tip_down = axis_angle({0, 1, 0}, 0.5 * std::numbers::pi);
  const DropResult tip = drop(tip_down, 0.5, 0.6);
  std::printf("  tip down: rebound %.5f v0 (law: 0.5)\n", tip.vz_out);
  EXPECT_NEAR(tip.vz_out, 0.5, 5e-3);
  // Any orientation: dissipative law, no energy gain; elastic frictionless law, energy kept.
  const Quaternion orientations[] = {
      {}, axis_angle({0, 1, 0}, 0.3), axis_angle({1, 1, 0}, 1.0), axis_angle({0.3, 1, 0.2}, 2.2), tip_down};
  int k = 0;
  for (const auto& q : orientations) {
    const DropResult d = drop(q, 0.5, 0.6), e = drop(q, 1.0, 0.0);
    std::printf("  orientation %d: KE out/in %.4f (e = 0.5, mu = 0.6), %.6f (elastic, frictionless)\n", k++,
                d.ke_out / d.ke_in, e.ke_out / e.ke_in);
    EXPECT_LT(d.ke_out, d.ke_in);
    EXPECT_NEAR(e.ke_out / e.ke_in, 1.0, 1e-4);
  }
}

TEST(ShapedBodies, TiltedSpheroidComesToRestLyingFlatOnItsWeight) {
  const Material sand = make_material("sand", 2650);
  ContactModel model(LawKind::linear_spring_dashpot, {sand});
  model.set_pair(0, 0, ContactModel::linear_pair(1e4, 1e4, 0.5, 0.6));
  Walls walls;
  walls.add_plane({0, 0, 0}, {0, 0, 1}, 0);
  DemSettings s;
  s.skin = 0.2 * kRho;
  DemRig rig(MPI_COMM_SELF, {-3e-3, -3e-3, -1e-3}, {3e-3, 3e-3, 3e-3}, model, walls, s);
  rig.dem->set_shapes({seed_grain()});
  rig.dem->add_body(1, 0, 1, {0, 0, 0.9e-3}, axis_angle({0.2, 1, 0}, 0.6), {}, {});
  rig.dem->setup();
  const auto& p = rig.dem->particles();
  const int steps = static_cast<int>(0.6 / rig.dem->dt());
  for (int n = 0; n < steps; ++n) rig.dem->step();
  const DemStats st = rig.dem->stats();
  const double weight = p.mass[0] * 9.81;
  const double fz = rig.dem->wall_forces()[0].z;
  const Vec3 axis = orientation(p, 0).rotate({1, 0, 0});
  std::printf("  after %d steps: plane load / weight %.6f, long axis z %.4f, %ld spheres touching, KE %.3g J\n", steps,
              -fz / weight, axis.z, st.wall_contacts, st.kinetic_translational + st.kinetic_rotational);
  EXPECT_NEAR(-fz / weight, 1.0, 1e-4);
  EXPECT_LT(std::fabs(axis.z), 0.1);  // lying flat (faceted envelope: a few degrees)
  EXPECT_GE(st.wall_contacts, 2);
  EXPECT_LT(st.kinetic_translational + st.kinetic_rotational, 1e-6 * weight * kB);
}

TEST(ShapedBodies, ContactBehaviourConvergesWithSphereCount) {
  // The seed's grain lying on a plane rests with its centre b = 0.26 mm above it (true surface); its
  // contact spheres (tangent to the inscribed mesh surface) let it sink by the envelope's gap near
  // the bottom. The drop of the flat grain, rebound and peak load, shows how the collision itself
  // depends on the sphere count (several spheres touch at once: stiffer, less damped).
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  ellipsoid_mesh({kA, kB, kB}, 5, 9, nodes, tets);
  const Material sand = make_material("sand", 2650);
  ContactModel model(LawKind::linear_spring_dashpot, {sand});
  model.set_pair(0, 0, ContactModel::linear_pair(1e4, 1e4, 0.5, 0.6));
  std::printf("  spheres  rest height/b  flat drop: KE out/in  peak load/(m v0/t_c)\n");
  double previous_error = 1e300;
  for (const int count : {10, 20, 40, 75, 137}) {
    const ShapeTemplate grain = ShapeTemplate::from_mesh("grain", nodes, tets, count, kRho);
    const double mass = sand.density * grain.volume;
    // At rest.
    Walls walls;
    walls.add_plane({0, 0, 0}, {0, 0, 1}, 0);
    DemSettings s;
    s.skin = 0.2 * kRho;
    double rest = 0;
    {
      DemRig rig(MPI_COMM_SELF, {-3e-3, -3e-3, -1e-3}, {3e-3, 3e-3, 3e-3}, model, walls, s);
      rig.dem->set_shapes({grain});
      rig.dem->add_body(1, 0, 1, {0, 0, kB + 0.02e-3}, {}, {}, {});
      rig.dem->setup();
      const int steps = static_cast<int>(0.05 / rig.dem->dt());
      for (int n = 0; n < steps; ++n) rig.dem->step();
      rest = rig.dem->particles().x[2] / kB;
    }
    // Flat drop at 0.1 m/s, no gravity.
    s.gravity = {0, 0, 0};
    const double v0 = 0.1, tc = std::numbers::pi * std::sqrt(mass / 1e4);
    s.time_step = tc / 400;
    double ke_ratio = 0, peak = 0;
    {
      DemRig rig(MPI_COMM_SELF, {-3e-3, -3e-3, -1e-3}, {3e-3, 3e-3, 3e-3}, model, walls, s);
      rig.dem->set_shapes({grain});
      double low = 1e300;
      for (const auto& c : grain.spheres) low = std::min(low, c.z - kRho);
      rig.dem->add_body(1, 0, 1, {0, 0, -low + 1e-7}, {}, {0, 0, -v0}, {});
      rig.dem->setup();
      const double ke0 = 0.5 * mass * v0 * v0;
      bool touched = false;
      for (int n = 0; n < 20000; ++n) {
        rig.dem->step();
        const double load = std::fabs(rig.dem->wall_forces()[0].z);
        peak = std::max(peak, load);
        if (touched && load == 0.0) break;
        touched = touched || load > 0.0;
      }
      const DemStats st = rig.dem->stats();
      ke_ratio = (st.kinetic_translational + st.kinetic_rotational) / ke0;
      peak /= mass * v0 / tc;
    }
    std::printf("  %7d  %13.4f  %20.4f  %20.3f\n", count, rest, ke_ratio, peak);
    const double error = std::fabs(rest - 1);
    EXPECT_LT(error, previous_error * 1.05);  // no worse with more spheres
    previous_error = std::min(previous_error, error);
    EXPECT_LT(ke_ratio, 1.0);
  }
  EXPECT_LT(previous_error, 0.05);  // within 5 % of b with the most spheres
}

}  // namespace
}  // namespace tessera::test
