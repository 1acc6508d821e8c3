// SPDX-License-Identifier: MIT
#include "fluid/plic.hpp"

#include <algorithm>
#include <cmath>

namespace tessera::plic {
namespace {

// Components below this (after normalising to |n1| + |n2| + |n3| = 1) are taken as 0: the closed
// form divides by their product, and a plane within 1e-9 of axis-aligned is axis-aligned to the
// accuracy the reconstruction has anyway. The same rule serves V and its inverse, so they agree.
constexpr double kTinyComponent = 1e-9;

struct Sorted {
  double m1, m2, m3;  // 0 <= m1 <= m2 <= m3, m1 + m2 + m3 = 1
  double alpha;       // plane m . x = alpha in the unit cube, after flips
};

// Flips negative components (x_i -> 1 - x_i), normalises to a unit 1-norm and sorts.
bool canonical(double nx, double ny, double nz, double alpha, Sorted& c) {
  double m[3] = {nx, ny, nz};
  for (double& v : m)
    if (v < 0) {
      alpha -= v;
      v = -v;
    }
  const double sum = m[0] + m[1] + m[2];
  if (!(sum > 0)) return false;
  for (double& v : m) {
    v /= sum;
    if (v < kTinyComponent) v = 0;
  }
  const double s2 = m[0] + m[1] + m[2];
  for (double& v : m) v /= s2;
  std::sort(m, m + 3);
  c = {m[0], m[1], m[2], alpha / sum};
  return true;
}

// V for 0 <= a <= 1/2 (the other half by symmetry), sorted unit-sum normal (F5).
double volume_lower_half(double m1, double m2, double m3, double a) {
  const double m12 = m1 + m2;
  if (a < m1) return a * a * a / (6 * m1 * m2 * m3);
  if (a < m2) return a * (a - m1) / (2 * m2 * m3) + m1 * m1 / (6 * m2 * m3);
  if (a < std::min(m12, m3))
    return (a * a * (3 * m12 - a) + m1 * m1 * (m1 - 3 * a) + m2 * m2 * (m2 - 3 * a)) / (6 * m1 * m2 * m3);
  if (m3 < m12)
    return (a * a * (3 - 2 * a) + m1 * m1 * (m1 - 3 * a) + m2 * m2 * (m2 - 3 * a) + m3 * m3 * (m3 - 3 * a)) /
           (6 * m1 * m2 * m3);
  return (2 * a - m12) / (2 * m3);
}

double volume_sorted(const Sorted& c) {
  if (c.alpha <= 0) return 0;
  if (c.alpha >= 1) return 1;
  if (c.alpha <= 0.5) return volume_lower_half(c.m1, c.m2, c.m3, c.alpha);
  return 1 - volume_lower_half(c.m1, c.m2, c.m3, 1 - c.alpha);
}

// Inverse of volume_lower_half for 0 < f <= 1/2 (F5): closed form on the first two pieces and the
// linear one; safeguarded Newton on the two cubic pieces (monotone, at most a few iterations).
double alpha_lower_half(double m1, double m2, double m3, double f) {
  const double m12 = m1 + m2;
  if (m1 > 0) {
    const double v1 = m1 * m1 / (6 * m2 * m3);
    if (f < v1) return std::cbrt(6 * m1 * m2 * m3 * f);
  }
  if (m2 > 0) {
    const double v1 = m1 * m1 / (6 * m2 * m3);
    const double v2 = v1 + (m2 - m1) / (2 * m3);
    if (f < v2) return 0.5 * (m1 + std::sqrt(m1 * m1 + 8 * m2 * m3 * (f - v1)));
  }
  if (m1 == 0 || m3 >= m12) {
    const double v3 = m12 / (2 * m3);
    if (f >= v3 || m1 == 0) return m3 * f + 0.5 * m12;
  }
  // Cubic pieces: alpha in [m2, 1/2].
  double lo = m2, hi = 0.5;
  double a = 0.5 * (lo + hi);
  for (int it = 0; it < 60; ++it) {
    const double v = volume_lower_half(m1, m2, m3, a) - f;
    if (std::abs(v) < 1e-15) break;
    if (v > 0)
      hi = a;
    else
      lo = a;
    const double inv = 1.0 / (6 * m1 * m2 * m3);
    const double dv = a < std::min(m12, m3) ? (6 * m12 * a - 3 * a * a - 3 * m1 * m1 - 3 * m2 * m2) * inv
                                            : (6 * a - 6 * a * a - 3 * (m1 * m1 + m2 * m2 + m3 * m3)) * inv;
    double next = dv > 0 ? a - v / dv : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (hi - lo < 1e-16) break;
    a = next;
  }
  return a;
}

}  // namespace

double plane_volume(double nx, double ny, double nz, double alpha) {
  Sorted c;
  if (!canonical(nx, ny, nz, alpha, c)) return alpha > 0 ? 1.0 : 0.0;
  return volume_sorted(c);
}

double plane_alpha(double nx, double ny, double nz, double f) {
  double m[3] = {nx, ny, nz};
  double shift = 0;
  for (double& v : m)
    if (v < 0) {
      shift += v;  // alpha_original = alpha_flipped + sum of negative components
      v = -v;
    }
  const double sum = m[0] + m[1] + m[2];
  Sorted c;
  canonical(m[0], m[1], m[2], 0, c);
  double a;
  if (f <= 0)
    a = 0;
  else if (f >= 1)
    a = 1;
  else if (f <= 0.5)
    a = alpha_lower_half(c.m1, c.m2, c.m3, f);
  else
    a = 1 - alpha_lower_half(c.m1, c.m2, c.m3, 1 - f);
  return a * sum + shift;
}

double slab_volume(const double n[3], double alpha, int d, double s, bool high) {
  if (s <= 0) return 0;
  // Map the slab to the unit cube: x_d = x0 + s x'_d, so n . x = alpha becomes
  // n_d s x'_d + (others) = alpha - n_d x0.
  const double x0 = high ? 1 - s : 0;
  double m[3] = {n[0], n[1], n[2]};
  const double a = alpha - m[d] * x0;
  m[d] *= s;
  return s * plane_volume(m[0], m[1], m[2], a);
}

}  // namespace tessera::plic
