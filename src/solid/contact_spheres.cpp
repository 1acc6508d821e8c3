// SPDX-License-Identifier: MIT
#include "solid/contact_spheres.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/errors.hpp"

namespace tessera {

std::vector<std::array<int, 3>> boundary_triangles(const std::vector<Vec3>& nodes,
                                                   const std::vector<std::array<int, 4>>& tets) {
  // A face shared by two tetrahedra is interior; keep faces seen once, oriented away from the
  // tetrahedron's fourth vertex.
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 4>>> faces;
  for (const auto& t : tets)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 4> f{t[(k + 1) % 4], t[(k + 2) % 4], t[(k + 3) % 4], t[k]};  // last: opposite vertex
      std::array<int, 3> key{f[0], f[1], f[2]};
      std::sort(key.begin(), key.end());
      auto& e = faces[key];
      ++e.first;
      e.second = f;
    }
  std::vector<std::array<int, 3>> out;
  for (const auto& [key, e] : faces) {
    if (e.first != 1) continue;
    const auto& f = e.second;
    const Vec3 n = cross(nodes[f[1]] - nodes[f[0]], nodes[f[2]] - nodes[f[0]]);
    if (dot(n, nodes[f[3]] - nodes[f[0]]) > 0)
      out.push_back({f[0], f[2], f[1]});
    else
      out.push_back({f[0], f[1], f[2]});
  }
  return out;
}

ContactSpheres place_contact_spheres(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 4>>& tets,
                                     int count, double radius) {
  const auto surface = boundary_triangles(nodes, tets);
  std::vector<Vec3> normal(nodes.size());
  std::vector<char> on_surface(nodes.size(), 0);
  // Candidate anchors: surface nodes (area-weighted normals), then triangle centroids (face normals).
  std::vector<Vec3> point, dir;
  for (const auto& t : surface) {
    const Vec3 n = cross(nodes[t[1]] - nodes[t[0]], nodes[t[2]] - nodes[t[0]]);  // |n| = 2 area
    for (const int v : t) normal[v] += n, on_surface[v] = 1;
  }
  Vec3 centroid;
  for (std::size_t v = 0; v < nodes.size(); ++v)
    if (on_surface[v]) {
      point.push_back(nodes[v]);
      dir.push_back(normal[v] / norm(normal[v]));
      centroid += nodes[v];
    }
  centroid = centroid / static_cast<double>(point.size());
  for (const auto& t : surface) {
    const Vec3 n = cross(nodes[t[1]] - nodes[t[0]], nodes[t[2]] - nodes[t[0]]);
    point.push_back((nodes[t[0]] + nodes[t[1]] + nodes[t[2]]) / 3.0);
    dir.push_back(n / norm(n));
  }
  if (count < 1 || count > static_cast<int>(point.size()))
    throw InputError(
        "shape.contact_spheres", std::to_string(count),
        "between 1 and the number of surface nodes plus surface triangles (" + std::to_string(point.size()) + ")");
  // Farthest-point sampling: each new anchor is the candidate farthest from those chosen.
  std::vector<double> gap(point.size(), std::numeric_limits<double>::infinity());
  std::size_t next = 0;
  double far = -1;
  for (std::size_t k = 0; k < point.size(); ++k)
    if (const double d = norm2(point[k] - centroid); d > far) far = d, next = k;
  ContactSpheres out;
  out.radius = radius;
  for (int s = 0; s < count; ++s) {
    const Vec3 anchor = point[next];
    out.centres.push_back(anchor - dir[next] * radius);
    double best = -1;
    for (std::size_t k = 0; k < point.size(); ++k) {
      gap[k] = std::min(gap[k], norm2(point[k] - anchor));
      if (gap[k] > best) best = gap[k], next = k;
    }
  }
  return out;
}

EnvelopeDeviation envelope_deviation(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 3>>& surface,
                                     const ContactSpheres& spheres) {
  std::vector<Vec3> samples;
  for (const auto& t : surface) {
    samples.push_back((nodes[t[0]] + nodes[t[1]] + nodes[t[2]]) / 3.0);
    for (const int v : t) samples.push_back(nodes[v]);
  }
  EnvelopeDeviation e;
  double sum2 = 0;
  for (const auto& p : samples) {
    double d = std::numeric_limits<double>::infinity();
    for (const auto& c : spheres.centres) d = std::min(d, norm(p - c) - spheres.radius);
    e.gap = std::max(e.gap, d);
    e.overshoot = std::max(e.overshoot, -d);
    sum2 += d * d;
  }
  e.rms = std::sqrt(sum2 / static_cast<double>(samples.size()));
  return e;
}

}  // namespace tessera
