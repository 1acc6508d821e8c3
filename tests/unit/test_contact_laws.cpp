// SPDX-License-Identifier: MIT
// Contact laws in isolation: damping from restitution, the friction cap, history handling.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "solid/contact_model.hpp"

namespace tessera {
namespace {

TEST(ContactLaws, LinearZetaReproducesRestitution) {
  for (double e : {0.1, 0.5, 0.9, 1.0}) {
    const double z = ContactModel::linear_zeta_for_restitution(e);
    // Damped oscillator: e = exp(-pi zeta / sqrt(1 - zeta^2)).
    EXPECT_NEAR(std::exp(-std::numbers::pi * z / std::sqrt(1 - z * z)), e, 1e-12);
  }
}

TEST(ContactLaws, HertzAlphaRoundTrip) {
  for (double e : {0.2, 0.5, 0.8, 0.98}) {
    const double a = ContactModel::hertz_alpha_for_restitution(e);
    EXPECT_NEAR(ContactModel::hertz_restitution_for_alpha(a), e, 1e-6);
  }
  EXPECT_EQ(ContactModel::hertz_alpha_for_restitution(1.0), 0.0);
  // More damping, less rebound.
  EXPECT_GT(ContactModel::hertz_alpha_for_restitution(0.3), ContactModel::hertz_alpha_for_restitution(0.6));
}

TEST(ContactLaws, FrictionCapsTangentialForceAndSpring) {
  const auto c = LinearSpringDashpot::coefficients(ContactModel::linear_pair(1000.0, 1000.0, 1.0, 0.5), 1e-3, 1e-3);
  Vec3 xi{};
  // Large tangential slip: |F_t| must equal mu |F_n| and the spring hold exactly that force (T4).
  const Vec3 f = contact_force<LinearSpringDashpot>(c, 1e-3, {0, 0, 1}, {2.0, 0, 0}, 1e-3, xi);
  EXPECT_NEAR(f.z, 1.0, 1e-12);
  EXPECT_NEAR(std::hypot(f.x, f.y), 0.5, 1e-12);
  EXPECT_LT(f.x, 0.0);  // opposes the sliding velocity (eq. 6)
  EXPECT_NEAR(1000.0 * std::fabs(xi.x), 0.5, 1e-12);
}

TEST(ContactLaws, StickingContactBuildsTheSpringLinearly) {
  const auto c = LinearSpringDashpot::coefficients(ContactModel::linear_pair(1000.0, 400.0, 1.0, 10.0), 1e-3, 1e-3);
  Vec3 xi{};
  Vec3 f;
  for (int i = 0; i < 10; ++i) f = contact_force<LinearSpringDashpot>(c, 1e-3, {0, 0, 1}, {1e-3, 0, 0}, 1e-4, xi);
  EXPECT_NEAR(xi.x, 10 * 1e-7, 1e-20);
  EXPECT_NEAR(f.x, -400.0 * 1e-6, 1e-15);  // no damping (e = 1): F_t = -k_t xi
}

TEST(ContactLaws, HistoryIsRotatedOntoTangentPlaneKeepingLength) {
  const auto c = LinearSpringDashpot::coefficients(ContactModel::linear_pair(1000.0, 1000.0, 1.0, 10.0), 1e-3, 1e-3);
  for (const double tilt : {1e-5, 0.3}) {  // series branch and exact branch
    Vec3 xi{5e-4 * std::cos(tilt), 0, 5e-4 * std::sin(tilt)};
    contact_force<LinearSpringDashpot>(c, 1e-3, {0, 0, 1}, {0, 0, 0}, 1e-3, xi);
    EXPECT_NEAR(xi.z, 0.0, 1e-18);
    EXPECT_NEAR(std::hypot(xi.x, xi.y), 5e-4, 1e-18);
  }
}

TEST(ContactLaws, HertzNormalForceIsNeverAttractive) {
  const Material m{"m", 2500, 7e10, 0.3};
  const auto c = HertzMindlin::coefficients(ContactModel::hertz_mindlin_pair(m, m, 0.2, 0.0), 1e-3, 1e-3);
  Vec3 xi{};
  // Separating fast at tiny overlap: the dashpot would pull; the law clamps to zero.
  const Vec3 f = contact_force<HertzMindlin>(c, 1e-12, {0, 0, 1}, {0, 0, 10.0}, 1e-6, xi);
  EXPECT_GE(f.z, 0.0);
}

}  // namespace
}  // namespace tessera
