// SPDX-License-Identifier: MIT
// The free rigid-body rotation integrator (src/solid/rigid_rotation.hpp) against the torque-free
// asymmetric top (Euler's equations; Landau & Lifshitz, Mechanics, section 37).
//
// Reference: with I1 < I2 < I3 and L^2 > 2 E I2 the body-frame angular velocity about the
// intermediate axis is w2(t) ~ sn(lambda t, m), lambda = sqrt((I3 - I2)(L^2 - 2 E I1) / (I1 I2 I3)),
// m = (I2 - I1)(2 E I3 - L^2) / ((I3 - I2)(L^2 - 2 E I1)); w2 changes sign every 2 K(m) / lambda:
// the intermediate-axis (Dzhanibekov) flip. Near the separatrix the flips are sudden and rare.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "solid/rigid_rotation.hpp"

namespace tessera {
namespace {

double complete_elliptic_k(double m) {
  double a = 1.0, b = std::sqrt(1.0 - m);
  for (int i = 0; i < 40; ++i) {
    const double an = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = an;
  }
  return std::numbers::pi / (2.0 * a);
}

struct Top {
  Vec3 inertia{1.0, 2.0, 3.0};
  Vec3 L_body;
  Quaternion q;
  double energy() const {
    return 0.5 * (L_body.x * L_body.x / inertia.x + L_body.y * L_body.y / inertia.y + L_body.z * L_body.z / inertia.z);
  }
};

Top spinning_near_intermediate_axis() {
  Top t;
  const Vec3 w{0.01, 1.0, 0.01};  // mostly about axis 2
  t.L_body = {t.inertia.x * w.x, t.inertia.y * w.y, t.inertia.z * w.z};
  return t;
}

// Energy error bounded, world angular momentum and |q| preserved to round-off, over 10^6 steps
// (about 16 flips) at |w| dt = 0.01.
TEST(RigidRotation, TorqueFreeAsymmetricBodyConservesEnergyAndMomentum) {
  Top t = spinning_near_intermediate_axis();
  const double e0 = t.energy();
  const Vec3 L0 = t.q.rotate(t.L_body);
  double worst_e = 0, worst_L = 0, worst_q = 0;
  for (int n = 1; n <= 1000000; ++n) {
    free_rotation_step(t.q, t.L_body, t.inertia, 0.01);
    if (n % 1000 == 0) {
      worst_e = std::max(worst_e, std::fabs(t.energy() / e0 - 1));
      worst_L = std::max(worst_L, norm(t.q.rotate(t.L_body) - L0) / norm(L0));
      worst_q = std::max(worst_q, std::fabs(t.q.norm2() - 1));
    }
  }
  std::printf("  1e6 steps: |dE/E| <= %.2e, |dL|/|L| <= %.2e, ||q|^2 - 1| <= %.2e\n", worst_e, worst_L, worst_q);
  EXPECT_LT(worst_e, 1e-4);  // bounded O((w dt)^2) oscillation, no drift
  EXPECT_LT(worst_L, 1e-11);
  EXPECT_LT(worst_q, 1e-14);
}

TEST(RigidRotation, IntermediateAxisFlipPeriodMatchesAnalytic) {
  Top t = spinning_near_intermediate_axis();
  const double I1 = t.inertia.x, I2 = t.inertia.y, I3 = t.inertia.z;
  const double E = t.energy(), L2 = norm2(t.L_body);
  ASSERT_GT(L2, 2 * E * I2);
  const double lambda = std::sqrt((I3 - I2) * (L2 - 2 * E * I1) / (I1 * I2 * I3));
  const double m = (I2 - I1) * (2 * E * I3 - L2) / ((I3 - I2) * (L2 - 2 * E * I1));
  const double half_period = 2 * complete_elliptic_k(m) / lambda;

  const double dt = 1e-3;
  std::vector<double> flips;
  double previous = t.L_body.y, time = 0;
  while (flips.size() < 5 && time < 20 * half_period) {
    free_rotation_step(t.q, t.L_body, t.inertia, dt);
    time += dt;
    if ((t.L_body.y < 0) != (previous < 0)) {
      // Linear interpolation of the zero crossing within the step.
      flips.push_back(time - dt * t.L_body.y / (t.L_body.y - previous));
    }
    previous = t.L_body.y;
  }
  ASSERT_EQ(flips.size(), 5u);
  for (std::size_t k = 1; k < flips.size(); ++k) {
    const double measured = flips[k] - flips[k - 1];
    std::printf("  flip %zu: %.6f (analytic %.6f)\n", k, measured, half_period);
    // Second-order splitting at |w| dt = 1e-3: period error ~ (w dt)^2, far below 1e-4.
    EXPECT_NEAR(measured / half_period, 1.0, 1e-4);
  }
}

TEST(RigidRotation, SymmetricTopPrecessesAtTheAnalyticRate) {
  // I1 = I2: the body-frame momentum precesses about axis 3 at (I3 - I1) / (I1 I3) L3.
  Top t;
  t.inertia = {2.0, 2.0, 1.0};
  t.L_body = {0.3, 0.0, 1.0};
  const double rate = (t.inertia.z - t.inertia.x) / (t.inertia.x * t.inertia.z) * t.L_body.z;
  const double dt = 1e-3, duration = 2.0;
  for (int n = 0; n < static_cast<int>(duration / dt + 0.5); ++n) free_rotation_step(t.q, t.L_body, t.inertia, dt);
  const double angle = std::atan2(t.L_body.y, t.L_body.x);
  // Euler: dL/dt = L x w in the body frame, so dphi/dt = L3 (I3 - I1) / (I1 I3) = rate.
  EXPECT_NEAR(angle, rate * duration, 1e-6);
  // L3 (hence |L_perp|) is a constant of the exact motion; the splitting's axis-1 and axis-2
  // sub-rotations exchange momentum with axis 3 at O(dt^2): measured 2e-8 at |w| dt = 1e-3.
  EXPECT_NEAR(std::hypot(t.L_body.x, t.L_body.y), 0.3, 1e-6);
  EXPECT_NEAR(norm(t.L_body), std::hypot(0.3, 1.0), 1e-12);  // |L| to round-off (1e4 rotations)
}

TEST(RigidRotation, BodiesTurnedTogetherTakeTheBitsOfEachTurnedAlone) {
  // free_rotation_steps<W> interleaves W bodies (the blast's drift, fracture_multirate.cpp); each
  // body must take the operations it takes alone, to the bit, whatever its neighbours in the batch:
  // different inertias, momenta and steps, one with half-angles past the series' range (libm's
  // sine and cosine there), one standing still.
  Quaternion q[4], alone[4];
  Vec3 L[4] = {{0.3, -1.2, 0.7}, {2.0, 0.1, -0.4}, {0.0, 0.0, 0.0}, {-0.5, 0.9, 1.1}};
  Vec3 L_alone[4];
  const Vec3 inertia[4] = {{1.0, 2.0, 3.0}, {0.2, 0.25, 0.3}, {1.0, 1.0, 1.0}, {5e-3, 7e-3, 9e-3}};
  const double dt[4] = {1e-3, 2e-2, 1e-3, 1e-5};
  for (int b = 0; b < 4; ++b) {
    q[b] = alone[b] = Quaternion{0.5, 0.5, -0.5, 0.5};
    L_alone[b] = L[b];
  }
  bool past_series = false;
  for (int n = 0; n < 1000; ++n) {
    past_series = past_series || std::fabs(0.5 * 0.5 * dt[1] * L[1].x / inertia[1].x) >= 1e-2;
    free_rotation_steps<4>(q, L, inertia, dt);
    for (int b = 0; b < 4; ++b) free_rotation_step(alone[b], L_alone[b], inertia[b], dt[b]);
  }
  EXPECT_TRUE(past_series);  // the second body's first sub-rotation leaves the series' range
  for (int b = 0; b < 4; ++b) {
    EXPECT_EQ(q[b].w, alone[b].w) << b;
    EXPECT_EQ(q[b].x, alone[b].x) << b;
    EXPECT_EQ(q[b].y, alone[b].y) << b;
    EXPECT_EQ(q[b].z, alone[b].z) << b;
    EXPECT_EQ(L[b].x, L_alone[b].x) << b;
    EXPECT_EQ(L[b].y, L_alone[b].y) << b;
    EXPECT_EQ(L[b].z, L_alone[b].z) << b;
  }
  // The still body stays where it was (its q only renormalised).
  EXPECT_NEAR(q[2].w, 0.5, 1e-15);
}

}  // namespace
}  // namespace tessera
