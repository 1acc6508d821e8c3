// SPDX-License-Identifier: MIT
// Test meshes: a spheroid with semi-axes (ax, r, r) as a fan of tetrahedra from its centre to a
// latitude-longitude surface mesh (n_lat rings, 2 n_lat meridians).
#pragma once
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/vec3.hpp"

namespace tessera::test {

inline void spheroid_fan(double ax, double r, int n_lat, std::vector<Vec3>& nodes,
                         std::vector<std::array<int, 4>>& tets) {
  const int n_lon = 2 * n_lat;
  nodes = {{0, 0, 0}, {ax, 0, 0}, {-ax, 0, 0}};
  tets.clear();
  for (int i = 1; i < n_lat; ++i)
    for (int j = 0; j < n_lon; ++j) {
      const double th = std::numbers::pi * i / n_lat, ph = 2 * std::numbers::pi * j / n_lon;
      nodes.push_back({ax * std::cos(th), r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph)});
    }
  auto ring = [&](int i, int j) { return 3 + (i - 1) * n_lon + (j % n_lon); };
  for (int j = 0; j < n_lon; ++j) {
    tets.push_back({0, 1, ring(1, j), ring(1, j + 1)});
    tets.push_back({0, 2, ring(n_lat - 1, j), ring(n_lat - 1, j + 1)});
    for (int i = 1; i + 1 < n_lat; ++i) {
      tets.push_back({0, ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      tets.push_back({0, ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  }
}

}  // namespace tessera::test
