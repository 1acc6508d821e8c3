// SPDX-License-Identifier: MIT
#include "fracture/face_spheres.hpp"

#include <algorithm>
#include <cmath>

#include "fracture/bonded_block.hpp"

namespace tessera {

namespace {

// Unit normal of local face f pointing into the tetrahedron.
Vec3 inward_normal(const std::array<Vec3, 4>& v, int f) {
  const Vec3 &a = v[kFaceVertices[f][0]], &b = v[kFaceVertices[f][1]], &c = v[kFaceVertices[f][2]];
  Vec3 n = cross(b - a, c - a);
  n = n / norm(n);
  return dot(n, v[f] - a) > 0 ? n : -n;
}

}  // namespace

std::vector<FaceSphere> face_spheres(const std::array<Vec3, 4>& v, int face, int divisions) {
  const Vec3 &p0 = v[kFaceVertices[face][0]], &p1 = v[kFaceVertices[face][1]], &p2 = v[kFaceVertices[face][2]];
  const Vec3 n = -inward_normal(v, face);
  std::vector<FaceSphere> out;
  for (int i = 1; i < divisions; ++i)
    for (int j = 1; i + j < divisions; ++j) {
      const int k = divisions - i - j;
      const Vec3 p = (p0 * i + p1 * j + p2 * k) / static_cast<double>(divisions);
      double r = 1e300;
      for (int g = 0; g < 4; ++g) {
        if (g == face) continue;
        const Vec3 m = inward_normal(v, g);
        const Vec3& a = v[kFaceVertices[g][0]];
        r = std::min(r, dot(p - a, m) / (1 + dot(n, m)));
      }
      out.push_back({p - n * r, r});
    }
  return out;
}

}  // namespace tessera
