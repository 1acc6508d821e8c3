// SPDX-License-Identifier: MIT
#include "coupling/layout_cost.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "coupling/solid_phase.hpp"

namespace tessera {

LayoutCost layout_cost(const std::vector<ShapeTemplate>& shapes, const std::vector<BodyPose>& bodies, const Vec3& lo,
                       const Vec3& spacing, const std::array<int, 3>& cells,
                       const std::array<std::vector<double>, 3>& slabs, int repeats) {
  const std::array<int, 3> dims{int(slabs[0].size()), int(slabs[1].size()), int(slabs[2].size())};
  const std::size_t ranks = std::size_t(dims[0]) * dims[1] * dims[2];
  // Each slab's first cell, per direction; and its box, open where it meets the domain's side (a
  // wall's cells take what lies beyond it, as SolidPhase::update's).
  std::array<std::vector<int>, 3> begin;
  std::array<std::vector<double>, 3> box_lo, box_hi;
  for (int d = 0; d < 3; ++d) {
    int at = 0;
    for (int s = 0; s < dims[d]; ++s) {
      begin[d].push_back(at);
      box_lo[d].push_back(s == 0 ? -HUGE_VAL : lo[d] + at * spacing[d]);
      at += int(slabs[d][std::size_t(s)]);
      box_hi[d].push_back(s + 1 == dims[d] ? HUGE_VAL : lo[d] + at * spacing[d]);
    }
    begin[d].push_back(at);
  }
  std::vector<double> reach;
  for (const ShapeTemplate& t : shapes) reach.push_back(farthest_node(t) * (1 + 1e-9));
  // The bodies each rank lays out: those whose farthest node can reach its box.
  std::vector<std::vector<std::size_t>> laid(ranks);
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    if (bodies[b].shape <= 0) continue;
    const double r = reach[std::size_t(bodies[b].shape - 1)];
    const Vec3& x = bodies[b].x;
    std::array<int, 3> s0{}, s1{};  // the slabs within r along each direction
    for (int d = 0; d < 3; ++d) {
      s0[d] = int(std::upper_bound(box_hi[d].begin(), box_hi[d].end(), x[d] - r) - box_hi[d].begin());
      s1[d] = int(std::lower_bound(box_lo[d].begin(), box_lo[d].end(), x[d] + r) - box_lo[d].begin()) - 1;
      s0[d] = std::min(s0[d], dims[d] - 1), s1[d] = std::max(s1[d], 0);
    }
    for (int k = s0[2]; k <= s1[2]; ++k)
      for (int j = s0[1]; j <= s1[1]; ++j)
        for (int i = s0[0]; i <= s1[0]; ++i) {
          const int c[3] = {i, j, k};
          double d2 = 0;
          for (int d = 0; d < 3; ++d) {
            const double out = std::max({box_lo[d][std::size_t(c[d])] - x[d], x[d] - box_hi[d][std::size_t(c[d])], 0.0});
            d2 += out * out;
          }
          if (d2 <= r * r) laid[std::size_t(i) + std::size_t(dims[0]) * (std::size_t(j) + std::size_t(dims[1]) * k)].push_back(b);
        }
  }
  LayoutCost cost;
  cost.seconds.assign(ranks, HUGE_VAL);
  cost.cells.assign(ranks, 0.0);
  cost.bodies.assign(ranks, 0.0);
  CellRasterizer raster;
  Polytope scratch;
  std::vector<Vec3> world;
  for (int rep = 0; rep < std::max(1, repeats); ++rep)
    for (std::size_t rank = 0; rank < ranks; ++rank) {
      const std::array<int, 3> c{int(rank % std::size_t(dims[0])), int((rank / std::size_t(dims[0])) % std::size_t(dims[1])),
                                 int(rank / (std::size_t(dims[0]) * std::size_t(dims[1])))};
      CellRange range{lo, {spacing[0], spacing[1], spacing[2]}, {}, {}, {0, 0, 0}, {cells[0] - 1, cells[1] - 1, cells[2] - 1}};
      for (int d = 0; d < 3; ++d)
        range.begin[d] = begin[d][std::size_t(c[d])], range.end[d] = begin[d][std::size_t(c[d]) + 1];
      long reported = 0;
      const auto start = std::chrono::steady_clock::now();
      for (const std::size_t b : laid[rank]) {
        const ShapeTemplate& t = shapes[std::size_t(bodies[b].shape - 1)];
        world.resize(t.nodes.size());
        for (std::size_t n = 0; n < t.nodes.size(); ++n) world[n] = bodies[b].x + bodies[b].q.rotate(t.nodes[n]);
        lay_out_body(t, world, range, raster, scratch, [&](int, int, int, double) { ++reported; });
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      cost.seconds[rank] = std::min(cost.seconds[rank], seconds);
      cost.cells[rank] = double(reported);
      cost.bodies[rank] = double(laid[rank].size());
    }
  return cost;
}

}  // namespace tessera
