// SPDX-License-Identifier: MIT
#include "fracture/bonded_block.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <tuple>

#include "core/errors.hpp"
#include "core/morton.hpp"
#include "solid/tet_mass_properties.hpp"

namespace tessera {

void face_frame(const BondedBlock& b, int e, int f, Vec3& normal, Vec3& centroid, double& area) {
  const auto& v = b.vertices[static_cast<std::size_t>(e)];
  const Vec3 &p0 = v[kFaceVertices[f][0]], &p1 = v[kFaceVertices[f][1]], &p2 = v[kFaceVertices[f][2]];
  Vec3 n = cross(p1 - p0, p2 - p0);
  area = 0.5 * norm(n);
  n = n / norm(n);
  centroid = (p0 + p1 + p2) / 3.0;
  if (dot(n, v[f] - centroid) > 0) n = -n;  // away from the opposite vertex
  normal = n;
}

BondedBlock build_bonded_block(const TetMesh& mesh, double density) {
  BondedBlock b;
  b.nodes = mesh.nodes;
  const std::size_t n = mesh.tetrahedra.size();
  if (n == 0) throw InputError("blast.mesh", "", "a mesh with tetrahedra (none found)");
  // Elements by the Morton code of their vertices' mean in the nodes' box, ties by the file's order.
  Vec3 lo = b.nodes.front(), hi = lo;
  for (const Vec3& p : b.nodes)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d]);
  std::vector<std::uint64_t> code(n);
  for (std::size_t e = 0; e < n; ++e) {
    Vec3 c{};
    for (int k : mesh.tetrahedra[e]) c += b.nodes[static_cast<std::size_t>(k)];
    code[e] = morton(c / 4.0, lo, hi);
  }
  b.mesh_index.resize(n);
  std::iota(b.mesh_index.begin(), b.mesh_index.end(), 0);
  std::stable_sort(b.mesh_index.begin(), b.mesh_index.end(),
                   [&](int a, int c) { return code[static_cast<std::size_t>(a)] < code[static_cast<std::size_t>(c)]; });
  b.tets.resize(n);
  for (std::size_t e = 0; e < n; ++e) b.tets[e] = mesh.tetrahedra[static_cast<std::size_t>(b.mesh_index[e])];
  b.mass.resize(n), b.volume.resize(n), b.inertia.resize(n), b.x0.resize(n), b.q0.resize(n), b.vertices.resize(n);
  b.min_edge = 1e300;
  for (std::size_t e = 0; e < n; ++e) {
    const MassProperties mp = tet_mass_properties(b.nodes, {b.tets[e]}, density);
    b.mass[e] = mp.mass, b.volume[e] = mp.volume, b.inertia[e] = mp.principal_moments, b.x0[e] = mp.centroid;
    const auto& A = mp.principal_axes;
    b.q0[e] = quaternion_from_axes(A[0], A[1], A[2]);
    for (int k = 0; k < 4; ++k) {
      const Vec3 d = b.nodes[static_cast<std::size_t>(b.tets[e][k])] - mp.centroid;
      b.vertices[e][k] = {dot(d, A[0]), dot(d, A[1]), dot(d, A[2])};
      for (int l = k + 1; l < 4; ++l) {
        const double len = norm(b.nodes[static_cast<std::size_t>(b.tets[e][k])] - b.nodes[static_cast<std::size_t>(b.tets[e][l])]);
        b.min_edge = std::min(b.min_edge, len), b.max_edge = std::max(b.max_edge, len);
      }
    }
  }
  // Faces by their sorted node triple.
  std::map<std::array<int, 3>, std::vector<std::pair<int, int>>> faces;
  for (std::size_t e = 0; e < n; ++e)
    for (int f = 0; f < 4; ++f) {
      std::array<int, 3> key{b.tets[e][kFaceVertices[f][0]], b.tets[e][kFaceVertices[f][1]], b.tets[e][kFaceVertices[f][2]]};
      std::sort(key.begin(), key.end());
      faces[key].push_back({static_cast<int>(e), f});
    }
  auto local_index = [&](int e, int node) {
    for (int k = 0; k < 4; ++k)
      if (b.tets[static_cast<std::size_t>(e)][k] == node) return k;
    return -1;
  };
  for (const auto& [key, owners] : faces) {
    if (owners.size() > 2)
      throw InputError("blast.mesh", "",
                       "a conforming tetrahedral mesh (a face, nodes " + std::to_string(key[0]) + ", " +
                           std::to_string(key[1]) + ", " + std::to_string(key[2]) + ", is shared by " +
                           std::to_string(owners.size()) + " tetrahedra)");
    if (owners.size() == 1) {
      SurfaceFace s;
      s.element = owners[0].first, s.face = owners[0].second, s.nodes = key;
      face_frame(b, s.element, s.face, s.normal_body, s.centroid_body, s.area);
      b.surface.push_back(s);
      continue;
    }
    auto [m, fm] = owners[0];
    auto [sl, fs] = owners[1];
    if (m > sl) std::swap(m, sl), std::swap(fm, fs);
    BondGeometry g;
    g.master = m, g.slave = sl, g.master_face = fm, g.slave_face = fs, g.nodes = key;
    Vec3 c;
    face_frame(b, m, fm, g.normal, c, g.area);
    for (int k = 0; k < 3; ++k) {
      g.at_master[k] = b.vertices[static_cast<std::size_t>(m)][local_index(m, key[k])];
      g.at_slave[k] = b.vertices[static_cast<std::size_t>(sl)][local_index(sl, key[k])];
    }
    g.xi = g.at_master[1] - g.at_master[0];
    g.xi = g.xi / norm(g.xi);
    g.eta = cross(g.normal, g.xi);
    b.bonds.push_back(g);
  }
  std::sort(b.bonds.begin(), b.bonds.end(),
            [](const BondGeometry& a, const BondGeometry& c) { return std::tie(a.master, a.slave) < std::tie(c.master, c.slave); });
  std::sort(b.surface.begin(), b.surface.end(),
            [](const SurfaceFace& a, const SurfaceFace& c) { return std::tie(a.element, a.face) < std::tie(c.element, c.face); });
  return b;
}

}  // namespace tessera
