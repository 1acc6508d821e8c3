// SPDX-License-Identifier: MIT
#include "analysis/bed_surface.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/all_gather.hpp"
#include "core/exact_sum.hpp"
#include "coupling/tet_clip.hpp"
#include "solid/dem_solver.hpp"

namespace tessera {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Quaternion orientation(const ParticleStore& p, std::size_t i) {
  return Quaternion{p.q[4 * i], p.q[4 * i + 1], p.q[4 * i + 2], p.q[4 * i + 3]};
}

// The rims on both sides of the axis along one grid line (heights h[0..2n], the axis at n) and the
// height midway between them (D5). Cells without grains (NaN) are skipped; none on a side: invalid.
bool measure_section(const std::vector<double>& h, int n, int reach, double cell, CraterSection& s) {
  int lo = -1, hi = -1;  // ties go to the cell nearer the axis
  for (int k = n - 1; k >= std::max(0, n - reach); --k)
    if (!std::isnan(h[k]) && (lo < 0 || h[k] > h[lo])) lo = k;
  for (int k = n + 1; k <= std::min(2 * n, n + reach); ++k)
    if (!std::isnan(h[k]) && (hi < 0 || h[k] > h[hi])) hi = k;
  if (lo < 0 || hi < 0) return false;
  s.a1 = h[lo];
  s.a2 = h[hi];
  s.length = (hi - lo) * cell;
  // Midway: the cell there, or between the two cells there; the nearest cells with grains if empty.
  auto nearest = [&](int k, int step) {
    while (k > lo && k < hi && std::isnan(h[k])) k += step;
    return h[k];
  };
  const int m0 = (lo + hi) / 2, m1 = (lo + hi + 1) / 2;
  s.b = 0.5 * (nearest(m0, -1) + nearest(m1, +1));
  return true;
}

}  // namespace

std::vector<GrainTop> grain_tops(const DemSolver& dem) {
  const ParticleStore& p = dem.particles();
  const auto& shapes = dem.shapes();
  std::vector<double> mine;  // id, x, y, top per shaped body
  for (std::size_t i = 0; i < p.owned; ++i) {
    if (p.shape[i] <= 0) continue;
    const Quaternion q = orientation(p, i);
    double top = -std::numeric_limits<double>::infinity();
    for (const Vec3& node : shapes[p.shape[i] - 1].nodes) top = std::max(top, q.rotate(node).z);
    mine.insert(mine.end(), {double(p.id[i]), p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2] + top});
  }
  const std::vector<double> all = all_gather_concat(dem.decomposition().comm(), mine);
  std::vector<std::size_t> order(all.size() / 4);
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return all[4 * a] < all[4 * b]; });
  std::vector<GrainTop> tops;
  tops.reserve(order.size());
  for (std::size_t k : order) tops.push_back({all[4 * k + 1], all[4 * k + 2], all[4 * k + 3]});
  return tops;
}

double solid_volume_below(const DemSolver& dem, double z) {
  const ParticleStore& p = dem.particles();
  const auto& shapes = dem.shapes();
  ExactSum sum;
  for (std::size_t i = 0; i < p.owned; ++i) {
    if (p.shape[i] <= 0) continue;
    const ShapeTemplate& t = shapes[p.shape[i] - 1];
    const Quaternion q = orientation(p, i);
    const Vec3 c = p.pos(i);
    if (c.z - t.bounding_radius >= z) continue;
    const Vec3 lo{c.x - 2 * t.bounding_radius, c.y - 2 * t.bounding_radius, c.z - 2 * t.bounding_radius};
    const Vec3 hi{c.x + 2 * t.bounding_radius, c.y + 2 * t.bounding_radius, z};
    for (const auto& tet : t.tetrahedra) {
      Tet w;
      for (int v = 0; v < 4; ++v) w[v] = c + q.rotate(t.nodes[tet[v]]);
      sum += tet_box_volume(w, lo, hi);
    }
  }
  sum.all_reduce(dem.decomposition().comm());
  return sum.value();
}

double bed_top(const std::vector<GrainTop>& tops, double cx, double cy, double radius) {
  double top = -std::numeric_limits<double>::infinity();
  for (const GrainTop& g : tops)
    if ((g.x - cx) * (g.x - cx) + (g.y - cy) * (g.y - cy) < radius * radius) top = std::max(top, g.top);
  return top;
}

Crater measure_crater(const std::vector<GrainTop>& tops, const CraterSettings& s) {
  Crater c;
  const int n = c.n = int(std::ceil(s.max_radius / s.cell));
  const int w = 2 * n + 1;
  // D2: the highest top of each cell, then the mean of the tops within surface_layer of it.
  std::vector<double> highest(std::size_t(w) * w, -std::numeric_limits<double>::infinity());
  auto cell_of = [&](const GrainTop& g) -> long {
    const long i = std::lround((g.x - s.cx) / s.cell), j = std::lround((g.y - s.cy) / s.cell);
    if (i < -n || i > n || j < -n || j > n) return -1;
    return (j + n) * w + (i + n);
  };
  for (const GrainTop& g : tops)
    if (const long k = cell_of(g); k >= 0) highest[k] = std::max(highest[k], g.top);
  std::vector<double> sum(highest.size(), 0.0);
  std::vector<int> count(highest.size(), 0);
  for (const GrainTop& g : tops)  // in id order: the same sums on any rank count
    if (const long k = cell_of(g); k >= 0 && g.top >= highest[k] - s.surface_layer) sum[k] += g.top, ++count[k];
  c.height.assign(highest.size(), kNaN);
  for (std::size_t k = 0; k < highest.size(); ++k)
    if (count[k]) c.height[k] = sum[k] / count[k];
  // D3: rings about the axis.
  const int rings = std::max(1, int(std::floor(s.max_radius / s.ring_width)));
  std::vector<double> ring_sum(rings, 0.0);
  c.ring_cells.assign(rings, 0);
  for (int j = -n; j <= n; ++j)
    for (int i = -n; i <= n; ++i) {
      const double h = c.height[std::size_t(j + n) * w + (i + n)];
      const int k = int(std::floor(std::hypot(i * s.cell, j * s.cell) / s.ring_width));
      if (std::isnan(h) || k >= rings) continue;
      ring_sum[k] += h;
      ++c.ring_cells[k];
    }
  c.ring_radius.resize(rings);
  c.ring_height.resize(rings);
  for (int k = 0; k < rings; ++k) {
    c.ring_radius[k] = (k + 0.5) * s.ring_width;
    c.ring_height[k] = c.ring_cells[k] ? ring_sum[k] / c.ring_cells[k] : kNaN;
  }
  // D4: b on the axis ring, a and L at the highest ring, V of the spherical cap (eq. 14).
  int top = -1;
  for (int k = 1; k < rings; ++k)
    if (!std::isnan(c.ring_height[k]) && (top < 0 || c.ring_height[k] > c.ring_height[top])) top = k;
  if (std::isnan(c.ring_height[0]) || top < 0) return c;
  c.b = c.ring_height[0];
  c.a = c.ring_height[top];
  c.rim_radius = c.ring_radius[top];
  c.depth = c.a - c.b;
  c.volume = std::numbers::pi * c.depth * (3 * c.rim_radius * c.rim_radius + c.depth * c.depth) / 6;
  // D5: the two sections through the axis, eq. 13.
  std::vector<double> along_x(w), along_y(w);
  for (int k = 0; k < w; ++k) along_x[k] = c.height[std::size_t(n) * w + k], along_y[k] = c.height[std::size_t(k) * w + n];
  const int reach = int(std::floor(s.max_radius / s.cell));
  if (!measure_section(along_x, n, reach, s.cell, c.section_x) || !measure_section(along_y, n, reach, s.cell, c.section_y))
    return c;
  const double h = 0.5 * (c.section_x.depth() + c.section_y.depth());
  const double l2 = c.section_x.length * c.section_y.length;
  c.section_volume = std::numbers::pi * h / 6 * (3 * l2 / 4 + h * h);
  c.valid = true;
  return c;
}

}  // namespace tessera
