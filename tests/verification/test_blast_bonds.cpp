// SPDX-License-Identifier: MIT
// The bonded tetrahedra of the blast scene (src/fracture; docs/theory.md B1-B9) against what the
// law and mechanics say exactly:
//   - a vertex unit's tension law: the envelope of B4 point by point, unloading to the origin and
//     reloading on the same line, and the work to break it equal to G_f (trapezoids on a piecewise
//     linear curve whose corners are sample points: exact up to round-off);
//   - in shear under a fixed compression sigma: the peak shear stress is c + sigma tan(phi), then
//     perfectly plastic (the slip takes the rest);
//   - two mirror-image tetrahedra pulled apart through their bond without dashpots: the kinetic
//     energy lost when the face breaks is G_f A (the trajectory's time error, O(dt^2) per unit of
//     work, bounded at 0.1 %; measured -0.001 %), momentum conserved to round-off;
//   - an intact bar's first longitudinal mode has the wave speed sqrt(E / rho) of the same mesh's
//     static modulus E (a separate linear solve of the springs), within 0.5 %;
//   - an intact bar without dashpots keeps its energy (velocity Verlet: bounded, O(dt^2) error;
//     the contact spheres of its surface faces must not touch across intact bonds);
//   - per-element levels (B10): a small fast element hitting a large one on another level conserves
//     momentum to round-off (both ways of sharing impulses); a bonded pair on levels 0 and 3 keeps
//     its energy within a bound;
//   - a bar shattered by a fast impact gives the same bits on 1, 2 and 4 ranks, with the bond
//     dashpots explicit or solved together (B9a), and keeps its momentum to round-off;
//   - the two halves of a cut bar thrown, spinning, at each other across a gap: the same bits whether
//     or not the pairs that cannot touch yet are skipped (B7a), both steppings, on 1, 2 and 4 ranks;
//   - a face released while pressed 0.1 mm in (B7b): its pairs, born overlapping, throw nothing
//     (84 J without the rule); pushed further in at 1 m/s the two bounce back elastically, the pairs
//     ordinary again once open; the same bits with the two elements on two ranks as on one;
//   - the borehole's gas (B8, B8a) on the seed's mesh at rest at the peak pressure: a wall element
//     takes exactly -P A n on each hole face (its unstrained bonds and spheres add nothing); a
//     fragment free in the gas (one element; two bonded elements) takes nothing, on either stepping;
//     a block split in two through the hole keeps the gas on both halves.
#include <gtest/gtest.h>
#include <mpi.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "fracture/fracture_solver.hpp"
#include "solid/gmsh_reader.hpp"
#include "support/fracture_fixture.hpp"

namespace tessera {
namespace {

using test::bar_mesh;
using World = test::FractureWorld;


TEST(BondLaw, TensionFollowsTheSofteningEnvelopeAndDissipatesGf) {
  BondLaw law;
  BondVertex s;
  const double uE = law.u_elastic(), uf = law.u_failure();
  ASSERT_TRUE(law.valid());
  EXPECT_NEAR(law.envelope(uE), law.tensile_strength, 1e-9 * law.tensile_strength);
  // Load to half-way down the softening branch, unload to zero, reload, then load to failure.
  const double um = 0.5 * (uE + uf);
  double work = 0, u_prev = 0, s_prev = 0;
  auto go = [&](double u) {
    const double sigma = bond_normal_stress(law, s, u);
    work += 0.5 * (sigma + s_prev) * (u - u_prev);
    u_prev = u, s_prev = sigma;
    return sigma;
  };
  const int n = 2000;
  for (int i = 1; i <= n; ++i) {
    const double u = um * i / n;
    const double sigma = go(u);
    const double expect = u <= uE ? law.kn * u : law.tensile_strength - law.softening() * (u - uE);
    ASSERT_NEAR(sigma, expect, 1e-9 * law.tensile_strength) << "loading, u = " << u;
  }
  const double sigma_m = law.envelope(um);
  for (int i = n - 1; i >= 0; --i) {  // unloading: the line to the origin
    const double u = um * i / n;
    ASSERT_NEAR(go(u), sigma_m / um * u, 1e-9 * law.tensile_strength) << "unloading, u = " << u;
  }
  const double under_envelope = 0.5 * law.tensile_strength * uE + 0.5 * (law.tensile_strength + sigma_m) * (um - uE);
  EXPECT_NEAR(work, under_envelope - 0.5 * sigma_m * um, 1e-6 * law.fracture_energy)
      << "the closed loop dissipates the triangle between the envelope and the unloading line";
  for (int i = 1; i <= 2 * n; ++i) {  // reloading past u_m to failure and beyond
    const double u = uf * 1.1 * i / (2 * n);
    const double sigma = go(u);
    const double expect = u <= um ? sigma_m / um * u : law.envelope(u);
    ASSERT_NEAR(sigma, expect, 1e-9 * law.tensile_strength) << "reloading, u = " << u;
  }
  EXPECT_NEAR(work, law.fracture_energy, 1e-6 * law.fracture_energy);
  EXPECT_DOUBLE_EQ(bond_damage(law, s), 1.0);
}

TEST(BondLaw, PeakShearUnderCompressionIsCohesionPlusFriction) {
  BondLaw law;
  for (const double sigma_c : {0.0, 2e6, 10e6}) {
    BondVertex s;
    const double un = -sigma_c / law.kn;
    double peak = 0;
    for (int i = 1; i <= 4000; ++i) {
      const double ut[2] = {3e-4 * i / 4000, 1e-4 * i / 4000};
      const double sigma = bond_normal_stress(law, s, un);
      double tau[2];
      bond_shear_stress(law, s, ut, sigma, tau);
      peak = std::max(peak, std::hypot(tau[0], tau[1]));
    }
    const double expect = law.cohesion + sigma_c * law.friction;
    EXPECT_NEAR(peak, expect, 1e-9 * expect) << "sigma = " << sigma_c;
    // Perfectly plastic: the slip took the displacement beyond the elastic one.
    EXPECT_NEAR(std::hypot(s.slip[0], s.slip[1]), std::hypot(3e-4, 1e-4) - expect / law.ks, 1e-12);
  }
}

// Two tetrahedra mirrored through their shared face z = 0 (apexes above the face's centroid), so the
// bond's three vertex forces pass through both centroids: pure translation.
TetMesh mirrored_pair(double a, double h) {
  TetMesh m;
  m.nodes = {{0, 0, 0}, {a, 0, 0}, {0, a, 0}, {a / 3, a / 3, h}, {a / 3, a / 3, -h}};
  m.tetrahedra = {{0, 1, 2, 3}, {0, 2, 1, 4}};
  return m;
}


TEST(BondedPair, BreakingTheFaceCostsGfTimesItsArea) {
  const double a = 0.05, h = 0.04;
  FractureSettings s;
  s.damping = false;
  s.stability_factor = 0.05;
  World w(MPI_COMM_SELF, mirrored_pair(a, h), s, {-1, -1, -1}, {1, 1, 1});
  FractureSolver& f = w.solver;
  ASSERT_EQ(f.block().bonds.size(), 1u);
  const double area = f.block().bonds[0].area, m = f.block().mass[0];
  // Enough kinetic energy to break it four times over.
  const double v0 = std::sqrt(4 * s.bond.fracture_energy * area / m);
  for (std::size_t e = 0; e < 2; ++e) f.set_velocity(e, {0, 0, f.block().x0[e].z > 0 ? v0 : -v0}, {});
  f.setup();
  const double e0 = f.energies().kinetic;
  while (f.broken_count() == 0 && f.steps() < 1000000) f.step();
  ASSERT_EQ(f.broken_count(), 1);
  f.step();  // the bond is gone: only kinetic energy is left
  const FractureEnergies en = f.energies();
  std::printf("pair: dissipated %.6g J, G_f A %.6g J (%+.3f %%)\n", e0 - en.kinetic, s.bond.fracture_energy * area,
              100 * ((e0 - en.kinetic) / (s.bond.fracture_energy * area) - 1));
  EXPECT_NEAR(e0 - en.kinetic, s.bond.fracture_energy * area, 1e-3 * s.bond.fracture_energy * area);
  const Vec3 p = f.v()[0] * f.block().mass[0] + f.v()[1] * f.block().mass[1];
  EXPECT_LT(norm(p), 1e-14 * m * v0);
  EXPECT_LT(norm(f.w()[0]) + norm(f.w()[1]), 1e-9 * v0 / a);  // no rotation from a centred pull
}

TEST(BondedBar, IntactBarWithoutDashpotsKeepsItsEnergy) {
  const double h = 0.02;
  FractureSettings s;
  s.damping = false;
  World w(MPI_COMM_SELF, bar_mesh(12, 2, 2, h), s, {-0.1, -0.1, -0.1}, {0.5, 0.2, 0.2});
  FractureSolver& f = w.solver;
  // A longitudinal mode-1 velocity profile, small enough to stay elastic.
  const double L = 12 * h;
  for (std::size_t e = 0; e < f.block().size(); ++e)
    f.set_velocity(e, {0.01 * std::cos(M_PI * f.block().x0[e].x / L), 0, 0}, {});
  f.setup();
  const FractureEnergies e0 = f.energies();
  const double total0 = e0.kinetic + e0.bond_elastic;
  double worst = 0;
  for (int i = 0; i < 4000; ++i) {
    f.step();
    if (i % 50 == 0) {
      const FractureEnergies e = f.energies();
      worst = std::max(worst, std::fabs(e.kinetic + e.bond_elastic - total0) / total0);
    }
  }
  EXPECT_EQ(f.broken_count(), 0);
  // Velocity Verlet's energy error is about (w dt)^2 / 8 of the stiffest mode: a face's k_n A on a
  // 3 g element, w ~ 3e5 rad/s, dt ~ 2e-8 s: ~5e-6.
  EXPECT_LT(worst, 1e-5) << "energy error of the intact bar (bounded; O(dt^2))";
}

// Two free tetrahedra of very different sizes (no shared face): a small fast one hits a large one.
TetMesh small_and_large() {
  TetMesh m;
  const double a = 0.1, b = 0.01;
  m.nodes = {{0, 0, 0},
             {a, 0, 0},
             {0, a, 0},
             {0, 0, a},  // large, its face x + y + z = a
             {0.035, 0.035, 0.035},
             {0.035 + b, 0.035, 0.035},
             {0.035, 0.035 + b, 0.035},
             {0.035, 0.035, 0.035 + b}};
  m.tetrahedra = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  return m;
}

TEST(Multirate, ElementsOnDifferentLevelsCollideConservingMomentum) {
  for (const Stepping stepping : {Stepping::stability, Stepping::travel}) {
    FractureSettings s;
    s.stepping = stepping;
    if (stepping == Stepping::travel) s.time_step = 1e-7, s.travel_limit = 2e-8;
    World w(MPI_COMM_SELF, small_and_large(), s, {-1, -1, -1}, {1, 1, 1});
    FractureSolver& f = w.solver;
    ASSERT_EQ(f.block().bonds.size(), 0u);
    f.set_velocity(1, {-2, -2, -2}, {0, 0, 50});  // the small one, towards the large one's slanted face
    f.setup();
    auto momentum = [&] { return f.v()[0] * f.block().mass[0] + f.v()[1] * f.block().mass[1]; };
    const Vec3 p0 = momentum();
    for (int i = 0; i < 40000 && f.v()[1].x == -2.0; ++i) f.step();
    ASSERT_NE(f.v()[1].x, -2.0) << "they touched";
    // The macro step of the first impulses: the small one still fast, on a finer level. (The contact
    // dashpot, ~200 times critical, makes the impact plastic: afterwards both may share level 0.)
    const int levels_apart = std::abs(f.levels()[0] - f.levels()[1]);
    for (int i = 0; i < 2000; ++i) f.step();
    EXPECT_GE(levels_apart, 1) << "different levels when they touched";
    EXPECT_NE(f.v()[0].x, 0.0) << "the large one was pushed";
    EXPECT_LT(norm(momentum() - p0), 1e-13 * norm(p0));
    EXPECT_GT(f.v()[1].x, -2.0) << "the small one was slowed";
  }
}

// B9a's level of an element held by contact pairs alone: the pairs that may touch (at rest: those
// that overlap) make a stiffness K = k_c sum J^T J (J = [n, r x n], r from the centroid to the
// pair's sphere) whose largest frequency, with the element's mass and world inertia, the level must
// resolve (stable), and whose bound k_c sum (1/m + sum_a (r x n)_a^2 / I_a) (each rank-one term's
// exact frequency, the terms' sum) sets it. Two mirror-image tetrahedra, their face released and
// the lower one pressed 0.1 mm in: the face's six pairs and the side faces' pairs near its edges.
TEST(Multirate, ContactLevelsResolveThePairsExactFrequency) {
  const double a = 0.05, h = 0.04, depth = 1e-4, dt0 = 1e-6;
  FractureSettings s;
  s.stepping = Stepping::stability;
  s.implicit_damping = true;  // B9a's levels: the springs that act
  s.time_step = dt0;          // no bond intact: no macro step from the bonds
  World w(MPI_COMM_SELF, mirrored_pair(a, h), s, {-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1});
  FractureSolver& f = w.solver;
  const BondedBlock& b = f.block();
  std::vector<Vec3> x = b.x0;
  const std::size_t low = b.x0[0].z < 0 ? 0 : 1;
  x[low].z += depth;
  const std::vector<Vec3> zero(2);
  ContactListState list;
  list.unlisted = {0};
  f.restore(x, b.q0, zero, zero, std::vector<std::array<BondVertex, 3>>(1), {1}, list, zero, zero);
  f.setup();
  f.step();  // at rest: the pairs born overlapping keep their depth (B7b), nothing moves
  // Every element's spheres (all four faces: three on the surface, the released one), in world frame.
  struct Placed {
    Vec3 c;
    double r;
  };
  std::vector<Placed> spheres[2];
  for (std::size_t e = 0; e < 2; ++e)
    for (int face = 0; face < 4; ++face)
      for (const FaceSphere& fs : face_spheres(b.vertices[e], face, s.sphere_divisions))
        spheres[e].push_back({x[e] + b.q0[e].rotate(fs.centre), fs.radius});
  for (std::size_t e = 0; e < 2; ++e) {
    Eigen::Matrix<double, 6, 6> K = Eigen::Matrix<double, 6, 6>::Zero(), M = Eigen::Matrix<double, 6, 6>::Zero();
    double bound = 0;
    int pairs = 0;
    const Vec3& I = b.inertia[e];
    for (const Placed& p : spheres[e])
      for (const Placed& o : spheres[1 - e]) {
        const Vec3 d = o.c - p.c;
        if (norm(d) - p.r - o.r > 0) continue;
        ++pairs;
        const Vec3 n = d / norm(d), rn = cross(p.c - x[e], n), t = b.q0[e].unrotate(rn);
        Eigen::Matrix<double, 6, 1> J;
        J << n.x, n.y, n.z, rn.x, rn.y, rn.z;
        K += s.contact_stiffness * J * J.transpose();
        bound += s.contact_stiffness * (1 / b.mass[e] + t.x * t.x / I.x + t.y * t.y / I.y + t.z * t.z / I.z);
      }
    ASSERT_GE(pairs, 6) << "the released face's six pairs at least";
    // M: the mass, and the world inertia R diag(I) R^T.
    Eigen::Matrix3d R;
    for (int c = 0; c < 3; ++c) {
      const Vec3 col = b.q0[e].rotate(Vec3{c == 0 ? 1.0 : 0.0, c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0});
      R.col(c) << col.x, col.y, col.z;
    }
    M.topLeftCorner<3, 3>() = b.mass[e] * Eigen::Matrix3d::Identity();
    M.bottomRightCorner<3, 3>() = R * Eigen::Vector3d(I.x, I.y, I.z).asDiagonal() * R.transpose();
    const double exact = Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(K, M, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
    int expected = 0;  // the smallest level whose step is within the factor of the bound's period
    while (std::ldexp(dt0, -expected) > s.stability_factor / std::sqrt(bound)) ++expected;
    const int level = f.levels()[e];
    std::printf("element %zu: %d pairs, largest frequency %.4g rad/s (bound %.4g), level %d\n", e, pairs,
                std::sqrt(exact), std::sqrt(bound), level);
    EXPECT_LE(exact, bound * (1 + 1e-12)) << "the bound bounds";
    EXPECT_GT(exact, 0.2 * bound) << "and not by much here";
    EXPECT_EQ(level, expected) << "the level of the bound, element " << e;
    EXPECT_LE(std::ldexp(dt0, -level) * std::sqrt(exact), s.stability_factor) << "resolved, element " << e;
  }
}

// Mirror-image tetrahedra of heights h and h/16 joined by their face: an elastic oscillation whose
// two elements sit on different levels (stability levels, impulses applied when made).
TEST(Multirate, MixedLevelsWithoutDashpotsKeepTheirEnergy) {
  const double a = 0.05, h = 0.04;
  TetMesh m;
  m.nodes = {{0, 0, 0}, {a, 0, 0}, {0, a, 0}, {a / 3, a / 3, h}, {a / 3, a / 3, -h / 16}};
  m.tetrahedra = {{0, 1, 2, 3}, {0, 2, 1, 4}};
  FractureSettings s;
  s.damping = false;
  s.stepping = Stepping::stability;
  World w(MPI_COMM_SELF, m, s, {-1, -1, -1}, {1, 1, 1});
  FractureSolver& f = w.solver;
  f.set_velocity(0, {0, 0, 1e-3}, {});
  f.set_velocity(1, {0, 0, -1e-3 * f.block().mass[0] / f.block().mass[1]}, {});
  f.setup();
  const FractureEnergies e0 = f.energies();
  double worst = 0;
  for (int i = 0; i < 3000; ++i) {
    f.step();
    const FractureEnergies e = f.energies();
    worst = std::max(worst, std::fabs(e.kinetic + e.bond_elastic - e0.kinetic) / e0.kinetic);
  }
  EXPECT_GE(std::abs(f.levels()[0] - f.levels()[1]), 2);
  std::printf("mixed levels %d %d: energy error %.3g over %.3g s\n", f.levels()[0], f.levels()[1], worst, f.time());
  // Bounded, not drifting (measured 2026-11-29: 0.22 % over 3,000 and over 30,000 macro steps).
  // Bound: a leapfrog's (w h)^2 / 8 for a mode at stability_factor (0.2) of an element's own
  // limit is 0.5 %; twice that.
  EXPECT_LT(worst, 1e-2);
}

// The static axial stiffness of a bonded mesh, from the linearised springs of B2 (independent of the
// solver's force code): 6 unknowns per element (displacement, small rotation), each vertex unit a
// pair of springs k_n A/3 along n and k_s A/3 across it between the two elements' points
// u = (x_j + th_j x r_j) - (x_i + th_i x r_i). Equal and opposite axial loads on the elements of
// the two end slabs; returns E = (P / A) / strain, the strain between two inner cross-sections.
double static_youngs_modulus(const BondedBlock& b, double length, double area, const BondLaw& law) {
  const int n = static_cast<int>(b.size());
  std::vector<Eigen::Triplet<double>> trip;
  for (const BondGeometry& g : b.bonds) {
    const Quaternion &qi = b.q0[static_cast<std::size_t>(g.master)], &qj = b.q0[static_cast<std::size_t>(g.slave)];
    const Vec3 nn = qi.rotate(g.normal);
    for (int k = 0; k < 3; ++k) {
      const Vec3 ri = qi.rotate(g.at_master[k]), rj = qj.rotate(g.at_slave[k]);
      // B (3 x 12): u = B [x_i, th_i, x_j, th_j]; th x r = -[r]x th.
      Eigen::Matrix<double, 3, 12> B = Eigen::Matrix<double, 3, 12>::Zero();
      auto skew = [](const Vec3& r) {
        Eigen::Matrix3d m;
        m << 0, -r.z, r.y, r.z, 0, -r.x, -r.y, r.x, 0;
        return m;
      };
      B.block<3, 3>(0, 0) = -Eigen::Matrix3d::Identity();
      B.block<3, 3>(0, 3) = skew(ri);
      B.block<3, 3>(0, 6) = Eigen::Matrix3d::Identity();
      B.block<3, 3>(0, 9) = -skew(rj);
      const Eigen::Vector3d nv(nn.x, nn.y, nn.z);
      const Eigen::Matrix3d D =
          g.area / 3 * (law.kn * nv * nv.transpose() + law.ks * (Eigen::Matrix3d::Identity() - nv * nv.transpose()));
      const Eigen::Matrix<double, 12, 12> K = B.transpose() * D * B;
      const int dof[2] = {6 * g.master, 6 * g.slave};
      for (int r = 0; r < 12; ++r)
        for (int c = 0; c < 12; ++c) trip.emplace_back(dof[r / 6] + r % 6, dof[c / 6] + c % 6, K(r, c));
    }
  }
  // A whisper of a spring to ground on every unknown removes the rigid modes (1e-9 of a bond's).
  for (int i = 0; i < 6 * n; ++i) trip.emplace_back(i, i, 1e-9 * law.kn * 1e-4);
  Eigen::SparseMatrix<double> K(6 * n, 6 * n);
  K.setFromTriplets(trip.begin(), trip.end());
  Eigen::VectorXd f = Eigen::VectorXd::Zero(6 * n);
  const double P = 1e3;  // N on each end
  std::vector<int> left, right;
  for (int e = 0; e < n; ++e) {
    if (b.x0[static_cast<std::size_t>(e)].x < 0.05 * length) left.push_back(e);
    if (b.x0[static_cast<std::size_t>(e)].x > 0.95 * length) right.push_back(e);
  }
  for (int e : left) f(6 * e) = -P / static_cast<double>(left.size());
  for (int e : right) f(6 * e) = P / static_cast<double>(right.size());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(K);
  const Eigen::VectorXd u = solver.solve(f);
  // Mean axial displacement of the elements in two thin slabs at 1/4 and 3/4 of the length.
  auto slab = [&](double at) {
    double sum = 0;
    int count = 0;
    for (int e = 0; e < n; ++e)
      if (std::fabs(b.x0[static_cast<std::size_t>(e)].x - at) < 0.04 * length) sum += u(6 * e), ++count;
    return sum / count;
  };
  const double strain = (slab(0.75 * length) - slab(0.25 * length)) / (0.5 * length);
  return P / area / strain;
}

TEST(BondedBar, WaveSpeedMatchesTheStaticStiffness) {
  // A 30 x 2 x 2 bar of 2 cm cubes, free at both ends, vibrating in its first longitudinal mode:
  // period 2 L / c. Reference: c = sqrt(E / rho) with E the same mesh's static modulus. The
  // discrete mesh's dispersion ((pi / 30)^2 / 24 = 5e-4) and the bar's lateral inertia (Rayleigh:
  // (nu pi r_g / L)^2 / 2 < 3e-4) put the two within 0.1 %; tolerance 0.5 %.
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) return;  // serial work: rank 0 alone
  const int nx = 30;
  const double h = 0.02, L = nx * h, area = 4 * h * h;
  FractureSettings s;
  s.damping = false;
  s.time_step = 4e-7;  // w dt ~ 0.15 for a face's spring on a 3 g element
  World w(MPI_COMM_SELF, bar_mesh(nx, 2, 2, h), s, {-0.1, -0.1, -0.1}, {L + 0.1, 0.2, 0.2});
  FractureSolver& f = w.solver;
  const double E = static_youngs_modulus(f.block(), L, area, s.bond);
  const double c_static = std::sqrt(E / s.density);
  for (std::size_t e = 0; e < f.block().size(); ++e)
    f.set_velocity(e, {1e-3 * std::cos(M_PI * f.block().x0[e].x / L), 0, 0}, {});
  f.setup();
  // The mode's amplitude: the end slabs' mean axial velocity; its sign changes every half period.
  auto end_velocity = [&] {
    double sum = 0;
    for (std::size_t e = 0; e < f.block().size(); ++e)
      if (f.block().x0[e].x < h) sum += f.v()[e].x;
    return sum;
  };
  std::vector<double> crossings;
  double prev = end_velocity(), t_prev = 0;
  const double period_guess = 2 * L / c_static;
  while (f.time() < 3.2 * period_guess) {
    f.step();
    const double now = end_velocity();
    if ((prev > 0) != (now > 0)) crossings.push_back(t_prev + (f.time() - t_prev) * prev / (prev - now));
    prev = now, t_prev = f.time();
  }
  ASSERT_GE(crossings.size(), 5u);
  const double period = 2 * (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  const double c_wave = 2 * L / period;
  std::printf("bar: E static %.4g GPa, c static %.5g m/s, c from the mode %.5g m/s (%+.3f %%)\n", E / 1e9, c_static,
              c_wave, 100 * (c_wave / c_static - 1));
  EXPECT_NEAR(c_wave, c_static, 5e-3 * c_static);
}

// Uniform steps, and stability levels (a rank drifts the other ranks' elements its pairs read: from
// the state their owner sent, they must take the owner's bits, spin included); each with the bond
// dashpots explicit, and solved together (B9a: the solve's inner products are exact sums; uniform
// steps then at 2e-7 s, three times B9's bound here). Every impulse is pairwise: the momentum of
// the start is kept to round-off.
TEST(BondedBar, ShatteringGivesTheSameBitsOnAnyRankCount) {
  int size = 1, rank = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const double h = 0.02;
  const TetMesh mesh = bar_mesh(10, 3, 2, h);
  const Vec3 lo{-0.01, -0.01, -0.01}, hi{0.21, 0.07, 0.05};
  for (const bool implicit : {false, true})
    for (const Stepping stepping : {Stepping::uniform, Stepping::stability}) {
      FractureSettings s;
      s.stepping = stepping;
      s.implicit_damping = implicit;
      if (implicit && stepping == Stepping::uniform) s.time_step = 2e-7;
      const int steps = implicit ? 600 : 1500;
      auto run = [&](MPI_Comm comm) {
        auto w = std::make_unique<World>(comm, mesh, s, lo, hi);
        FractureSolver& f = w->solver;
        // The left end is torn off at 60 m/s, spinning: faces break, spheres touch across ranks.
        for (std::size_t e = 0; e < f.block().size(); ++e)
          if (f.block().x0[e].x < 2 * h) f.set_velocity(e, {-60, 5, 0}, {0, 0, 300});
        f.setup();
        int finest = 0;
        for (int i = 0; i < steps; ++i) {
          f.step();
          for (int k : f.levels()) finest = std::max(finest, k);
        }
        f.sync_state();
        return std::make_pair(std::move(w), finest);
      };
      auto [here, finest] = run(MPI_COMM_WORLD);
      auto alone = run(MPI_COMM_SELF).first;
      const FractureSolver &a = here->solver, &b = alone->solver;
      const std::string name = std::string(stepping == Stepping::uniform ? "uniform" : "stability") +
                               (implicit ? ", dashpots solved together" : "");
      if (stepping == Stepping::stability) {
        EXPECT_GE(finest, 1) << "sub-steps (more than one level)";
      }
      EXPECT_GT(a.broken_count(), 5) << name;
      EXPECT_GT(a.contact_evaluations() + b.contact_evaluations(), 0) << name << ": spheres touched";
      EXPECT_EQ(a.broken_count(), b.broken_count()) << name;
      EXPECT_EQ(a.damping_iterations(), b.damping_iterations()) << name;
      EXPECT_EQ(a.damping_solves() > 0, implicit) << name;
      Vec3 p{}, p0{};
      for (std::size_t e = 0; e < a.block().size(); ++e) {
        p += a.v()[e] * a.block().mass[e];
        if (a.block().x0[e].x < 2 * h) p0 += Vec3{-60, 5, 0} * a.block().mass[e];
        ASSERT_EQ(a.x()[e].x, b.x()[e].x) << name << ", element " << e << " on " << size << " ranks, rank " << rank;
        ASSERT_EQ(a.x()[e].y, b.x()[e].y) << name;
        ASSERT_EQ(a.v()[e].z, b.v()[e].z) << name;
        ASSERT_EQ(a.q()[e].w, b.q()[e].w) << name;
        ASSERT_EQ(a.angular_momentum()[e].z, b.angular_momentum()[e].z) << name;
      }
      for (std::size_t k = 0; k < a.bond_state().size(); ++k)
        ASSERT_EQ(a.bond_state()[k][1].u_max, b.bond_state()[k][1].u_max) << name;
      EXPECT_LT(norm(p - p0), 1e-12 * norm(p0)) << name << ": momentum";
    }
}

TEST(Contacts, SkippingPairsThatCannotTouchGivesTheSameBits) {
  const double h = 0.02;
  const TetMesh mesh = bar_mesh(8, 2, 2, h);
  const Vec3 lo{-0.03, -0.03, -0.03}, hi{0.19, 0.07, 0.07};
  for (const Stepping stepping : {Stepping::uniform, Stepping::stability}) {
    auto run = [&](bool skip) {
      FractureSettings s;
      s.stepping = stepping;
      s.skip_apart = skip;
      auto w = std::make_unique<World>(MPI_COMM_WORLD, mesh, s, lo, hi);
      FractureSolver& f = w->solver;
      const BondedBlock& b = f.block();
      const std::size_t n = b.size();
      // Cut in the middle; the left half 0.5 mm back (its spheres listed: within the skin); the halves
      // thrown at each other, spinning about different axes.
      auto left = [&](int e) { return b.x0[static_cast<std::size_t>(e)].x < 4 * h; };
      std::vector<char> broken(b.bonds.size(), 0);
      for (std::size_t k = 0; k < b.bonds.size(); ++k) broken[k] = left(b.bonds[k].master) != left(b.bonds[k].slave);
      std::vector<Vec3> x = b.x0;
      for (std::size_t e = 0; e < n; ++e)
        if (left(static_cast<int>(e))) x[e].x -= 0.0005;
      const std::vector<Vec3> zero(n);
      f.restore(x, b.q0, zero, zero, std::vector<std::array<BondVertex, 3>>(b.bonds.size()), broken, ContactListState{},
                zero, zero);
      const Vec3 c{2 * h, h, h};  // the left half's middle
      for (std::size_t e = 0; e < n; ++e) {
        const Vec3 w_spin = left(static_cast<int>(e)) ? Vec3{30, 0, 0} : Vec3{0, 0, -20};
        const Vec3 centre = left(static_cast<int>(e)) ? c : c + Vec3{4 * h, 0, 0};
        f.set_velocity(e, Vec3{left(static_cast<int>(e)) ? 30.0 : -10.0, 0, 0} + cross(w_spin, x[e] - centre), w_spin);
      }
      f.setup();
      while (f.time() < 4e-5) f.step();  // the gap closes at 1.25e-5 s
      f.sync_state();
      return w;
    };
    auto skipped = run(true), every = run(false);
    const FractureSolver &a = skipped->solver, &c = every->solver;
    long counts[2] = {a.contact_evaluations(), c.contact_evaluations()};
    MPI_Allreduce(MPI_IN_PLACE, counts, 2, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0)
      std::printf("%s: contact evaluations %ld skipping, %ld without; %ld steps, %ld list builds, %ld refreshes\n",
                  stepping == Stepping::uniform ? "uniform" : "stability", counts[0], counts[1], a.steps(),
                  a.list_builds(), a.list_refreshes());
    EXPECT_LT(2 * counts[0], counts[1]) << "at least half of the evaluations skipped";
    // They met: some of the right half now moves to the right.
    double right_vx = -1e300;
    for (std::size_t e = 0; e < a.block().size(); ++e)
      if (a.block().x0[e].x > 4 * h) right_vx = std::max(right_vx, a.v()[e].x);
    EXPECT_GT(right_vx, 1.0) << "the halves collided";
    EXPECT_EQ(a.broken_count(), c.broken_count());
    for (std::size_t e = 0; e < a.block().size(); ++e) {
      ASSERT_EQ(a.x()[e].x, c.x()[e].x) << "element " << e;
      ASSERT_EQ(a.x()[e].z, c.x()[e].z) << "element " << e;
      ASSERT_EQ(a.v()[e].y, c.v()[e].y) << "element " << e;
      ASSERT_EQ(a.q()[e].x, c.q()[e].x) << "element " << e;
      ASSERT_EQ(a.angular_momentum()[e].y, c.angular_momentum()[e].y) << "element " << e;
    }
  }
}

TEST(Contacts, AFaceReleasedInCompressionThrowsNothingAndStillResists) {
  // B7b. Two mirror-image tetrahedra whose face has just been released (the bond broke at the
  // last step, its spheres not yet listed), the lower one pressed 0.1 mm into the upper one, as a
  // hinged face's compressed side is when its opened side fails. Its six sphere pairs are born
  // overlapping by exactly that depth.
  const double a = 0.05, h = 0.04, depth = 1e-4;
  // Two elements: at most two ranks (one each on two; the pairs then live on both).
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm comm = MPI_COMM_NULL;
  MPI_Comm_split(MPI_COMM_WORLD, rank < 2 ? 0 : MPI_UNDEFINED, rank, &comm);
  if (comm == MPI_COMM_NULL) return;
  for (const Stepping stepping : {Stepping::uniform, Stepping::stability}) {
    const char* name = stepping == Stepping::uniform ? "uniform" : "stability";
    auto run = [&](bool relax, double v_in, MPI_Comm on = MPI_COMM_NULL) {
      FractureSettings s;
      s.stepping = stepping;
      s.damping = false;  // elastic: what is thrown is what the springs were given
      s.relax_born_overlaps = relax;
      auto w = std::make_unique<World>(on == MPI_COMM_NULL ? comm : on, mirrored_pair(a, h), s, Vec3{-0.1, -0.1, -0.1},
                                       Vec3{0.1, 0.1, 0.1});
      FractureSolver& f = w->solver;
      const BondedBlock& b = f.block();
      const std::size_t low = b.x0[0].z < 0 ? 0 : 1;
      std::vector<Vec3> x = b.x0;
      x[low].z += depth;
      const std::vector<Vec3> zero(2);
      ContactListState list;
      list.unlisted = {0};  // released since the list was made
      f.restore(x, b.q0, zero, zero, std::vector<std::array<BondVertex, 3>>(1), {1}, list, zero, zero);
      f.set_velocity(low, {0, 0, v_in}, {});  // towards the upper one
      f.setup();
      while (f.time() < 3e-4) f.step();
      f.sync_state();
      return w;
    };
    // At rest: no force, nothing moves.
    {
      auto w = run(true, 0);
      const FractureSolver& f = w->solver;
      std::printf("%s: %ld pairs born overlapping, the deepest %.6g m\n", name, f.born_overlaps(), f.deepest_born_overlap());
      EXPECT_GE(f.born_overlaps(), 6) << name;
      EXPECT_NEAR(f.deepest_born_overlap(), depth, 1e-12) << name;
      EXPECT_LT(f.energies().kinetic, 1e-18) << name << ": at most round-off (45 J without B7b)";
      EXPECT_EQ(f.sunk_pairs(), static_cast<std::size_t>(f.born_overlaps())) << name << ": still sunk, at rest";
    }
    // The same without B7b: the springs throw the two apart with at least the energy the face's
    // six, each 0.1 mm deep, were given, 6 k depth^2 / 2 = 45 J (the other pairs born overlapping,
    // spheres of the side faces, add to it).
    {
      auto w = run(false, 0);
      const double thrown = w->solver.energies().kinetic, given = 6 * 0.5 * 1.5e9 * depth * depth;
      std::printf("%s without B7b: %.4g J thrown\n", name, thrown);
      EXPECT_GT(thrown, 0.9 * given) << name;
    }
    // Pushed further in at 1 m/s: the contact resists from where it was born, and the elastic
    // bounce sends the lower one back at 1 m/s relative; opened past zero overlap, the pairs are
    // ordinary again.
    {
      auto w = run(true, 1.0);
      const FractureSolver& f = w->solver;
      const std::size_t low = f.block().x0[0].z < 0 ? 0 : 1, up = 1 - low;
      const double closing = f.v()[low].z - f.v()[up].z;
      EXPECT_NEAR(closing, -1.0, 1e-2) << name << ": bounced";
      const double m = f.block().mass[0];
      EXPECT_NEAR(f.energies().kinetic, 0.5 * m * 1.0, 1e-2 * 0.5 * m) << name << ": elastic";
      EXPECT_EQ(f.sunk_pairs(), 0u) << name;
      EXPECT_LT(f.x()[low].z - f.x()[up].z, f.block().x0[low].z - f.block().x0[up].z) << name << ": apart";
      // The pair across two ranks (one element each) keeps the same depth on both: the same bits as
      // on one rank.
      auto alone = run(true, 1.0, MPI_COMM_SELF);
      for (std::size_t e = 0; e < 2; ++e) {
        EXPECT_EQ(f.x()[e].z, alone->solver.x()[e].z) << name;
        EXPECT_EQ(f.v()[e].z, alone->solver.v()[e].z) << name;
      }
    }
  }
  MPI_Comm_free(&comm);
}

TEST(Borehole, TheGasPushesTheWallAndNotAFragmentFreeInIt) {
  const TetMesh mesh = read_gmsh(std::string(TESSERA_SOURCE_DIR) + "/cases/blast/block.msh");
  Borehole hole;
  hole.centre = {0.6, 0.5, 0}, hole.axis = {0, 0, 1}, hole.radius = 0.025;
  for (const Stepping stepping : {Stepping::uniform, Stepping::stability}) {
    const char* name = stepping == Stepping::uniform ? "uniform" : "stability";
    FractureSettings s;
    s.stepping = stepping;
    Decomposition decomp(MPI_COMM_WORLD, {-0.01, -0.01, -0.01}, {1.01, 1.01, 0.21});
    FractureSolver f(decomp, build_bonded_block(mesh, s.density), s, hole);
    const BondedBlock& b = f.block();
    const std::size_t n = b.size();
    // Each element's hole faces' force at P0 at rest.
    std::vector<Vec3> gas(n);
    std::vector<double> gas_area(n, 0.0);
    for (int sf : f.hole_faces()) {
      const SurfaceFace& face = b.surface[static_cast<std::size_t>(sf)];
      const std::size_t e = static_cast<std::size_t>(face.element);
      gas[e] += b.q0[e].rotate(face.normal_body) * (-hole.p0 * face.area);
      gas_area[e] += face.area;
    }
    // The split: every bond across the plane y = 0.5 through the axis. A one-element chip e1 (the
    // first hole face's element) and a two-element chip e2 + n2 (a later hole face's element not
    // bonded to e1, and a neighbour of it): all their other bonds broken.
    std::vector<char> broken(b.bonds.size(), 0);
    for (std::size_t k = 0; k < b.bonds.size(); ++k)
      broken[k] = (b.x0[static_cast<std::size_t>(b.bonds[k].master)].y < 0.5) !=
                  (b.x0[static_cast<std::size_t>(b.bonds[k].slave)].y < 0.5);
    auto bonded_to = [&](int e, int g) {
      for (const BondGeometry& bond : b.bonds)
        if ((bond.master == e && bond.slave == g) || (bond.master == g && bond.slave == e)) return true;
      return false;
    };
    const int e1 = b.surface[static_cast<std::size_t>(f.hole_faces().front())].element;
    int e2 = -1, n2 = -1;
    for (int sf : f.hole_faces()) {
      const int e = b.surface[static_cast<std::size_t>(sf)].element;
      if (e != e1 && !bonded_to(e, e1)) e2 = e;
    }
    ASSERT_GE(e2, 0);
    for (std::size_t k = 0; k < b.bonds.size() && n2 < 0; ++k)
      if (b.bonds[k].master == e2 || b.bonds[k].slave == e2) {
        const int other = b.bonds[k].master == e2 ? b.bonds[k].slave : b.bonds[k].master;
        if (other != e1 && !bonded_to(other, e1)) n2 = other;
      }
    ASSERT_GE(n2, 0);
    for (std::size_t k = 0; k < b.bonds.size(); ++k) {
      const int m = b.bonds[k].master, sl = b.bonds[k].slave;
      const bool in_chip2 = (m == e2 && sl == n2) || (m == n2 && sl == e2);
      if (m == e1 || sl == e1 || m == e2 || sl == e2 || m == n2 || sl == n2) broken[k] = !in_chip2;
    }
    const std::vector<Vec3> zero(n);
    f.restore(b.x0, b.q0, zero, zero, std::vector<std::array<BondVertex, 3>>(b.bonds.size()), broken,
              ContactListState{}, zero, zero);
    f.set_clock(hole.rise, 0);  // P = P0
    ASSERT_EQ(hole.pressure(hole.rise), hole.p0);
    f.setup();
    // The fragments: the two chips at their own masses, both halves heavier than the hole's rock.
    const Fragments& frag = f.fragments();
    const auto mass_of = [&](int e) {
      return frag.mass[static_cast<std::size_t>(frag.label[static_cast<std::size_t>(e)])];
    };
    EXPECT_EQ(mass_of(e1), b.mass[static_cast<std::size_t>(e1)]) << name;
    EXPECT_EQ(mass_of(e2), b.mass[static_cast<std::size_t>(e2)] + b.mass[static_cast<std::size_t>(n2)]) << name;
    EXPECT_LT(mass_of(e2), f.hole_mass()) << name;
    int heavy = 0;
    for (double m : frag.mass) heavy += m >= f.hole_mass();
    EXPECT_EQ(heavy, 2) << name << ": the two halves";
    long chip_faces = 0;
    for (int sf : f.hole_faces()) {
      const int e = b.surface[static_cast<std::size_t>(sf)].element;
      chip_faces += e == e1 || e == e2 || e == n2;
    }
    EXPECT_EQ(f.unloaded_hole_faces(), chip_faces) << name;
    auto chip = [&](std::size_t e) { return e == std::size_t(e1) || e == std::size_t(e2) || e == std::size_t(n2); };
    int walls = 0;
    if (stepping == Stepping::uniform) {
      // The forces of the state at rest: the gas alone, on the wall's elements of both halves.
      for (std::size_t e = 0; e < n; ++e) {
        if (!f.owns(e) || gas_area[e] == 0) continue;
        const double scale = hole.p0 * gas_area[e];
        const Vec3 expect = chip(e) ? Vec3{} : gas[e];
        EXPECT_LT(norm(f.force()[e] - expect), 1e-9 * scale) << name << ", element " << e << (chip(e) ? " (chip)" : "");
        walls += !chip(e);
      }
    } else {
      // One macro step: the gas does not move the chips; a wall element takes about its impulse.
      f.step();
      f.sync_state();
      for (std::size_t e = 0; e < n; ++e) {
        if (gas_area[e] == 0) continue;
        const double dv =
            hole.p0 * gas_area[e] * f.dt() / b.mass[e];  // the gas's impulse over the macro step, per mass
        if (chip(e)) {
          // Its neighbours, pushed out by the gas, press on its spheres: measured 6.5e-4 dv at most.
          EXPECT_LT(norm(f.v()[e]), 1e-2 * dv) << name << ", chip element " << e;
        } else {
          EXPECT_GT(norm(f.v()[e]), 0.1 * dv) << name << ", wall element " << e;
          ++walls;
        }
      }
    }
    int all_walls = 0;
    MPI_Allreduce(&walls, &all_walls, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    EXPECT_GT(all_walls, 10) << name;
  }
}

}  // namespace
}  // namespace tessera
