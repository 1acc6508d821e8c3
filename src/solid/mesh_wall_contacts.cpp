// SPDX-License-Identifier: MIT
#include "solid/mesh_wall_contacts.hpp"

#include <algorithm>
#include <cmath>

#include "solid/triangle_contact.hpp"

namespace tessera {

double MeshWallContacts::displacement(const std::vector<MeshWall>& meshes) const {
  double d2 = 0;
  for (std::size_t m = 0; m < meshes.size() && m < nodes_at_find_.size(); ++m)
    for (std::size_t k = 0; k < meshes[m].nodes.size(); ++k)
      d2 = std::max(d2, norm2(meshes[m].nodes[k] - nodes_at_find_[m][k]));
  return std::sqrt(d2);
}

void MeshWallContacts::find(const ContactEntities& entities, const std::vector<MeshWall>& meshes, double skin) {
  entity_.clear(), mesh_of_.clear(), cands_.clear();
  cand_start_.assign(1, 0);
  nodes_at_find_.resize(meshes.size());
  if (meshes.empty()) return;
  const std::size_t n = entities.owned();
  auto centre = [&](std::size_t e) { return entities.centre(e); };
  auto radius = [&](std::size_t e) { return entities.radius(e); };
  double r_max = 0;
  for (std::size_t e = 0; e < n; ++e) r_max = std::max(r_max, radius(e));
  std::vector<int> found;
  for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
    const MeshWall& m = meshes[mi];
    nodes_at_find_[mi] = m.nodes;
    Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    double edge = 0;
    for (const auto& t : m.triangles)
      for (int a = 0; a < 3; ++a) {
        const Vec3& v = m.nodes[t[a]];
        for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], v[d]), hi[d] = std::max(hi[d], v[d]);
        edge = std::max(edge, norm(v - m.nodes[t[(a + 1) % 3]]));
      }
    const double reach = r_max + skin;
    double h = std::max(2 * reach, 0.5 * edge);
    int nc[3];
    for (;;) {
      double cells = 1;
      for (int d = 0; d < 3; ++d) cells *= (nc[d] = static_cast<int>((hi[d] - lo[d] + 2 * reach) / h) + 1);
      if (cells <= 4.0 * static_cast<double>(m.triangles.size()) + 64) break;
      h *= 1.5;
    }
    auto cell = [&](double x, int d) { return std::clamp(static_cast<int>((x - lo[d] + reach) / h), 0, nc[d] - 1); };
    auto at = [&](int x, int y, int z) { return (static_cast<std::size_t>(z) * nc[1] + y) * nc[0] + x; };
    std::vector<std::vector<int>> grid(static_cast<std::size_t>(nc[0]) * nc[1] * nc[2]);
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      int c0[3], c1[3];
      for (int d = 0; d < 3; ++d) {
        double a = 1e300, b = -1e300;
        for (int v = 0; v < 3; ++v) {
          a = std::min(a, m.nodes[m.triangles[t][v]][d]);
          b = std::max(b, m.nodes[m.triangles[t][v]][d]);
        }
        c0[d] = cell(a, d), c1[d] = cell(b, d);
      }
      for (int z = c0[2]; z <= c1[2]; ++z)
        for (int y = c0[1]; y <= c1[1]; ++y)
          for (int x = c0[0]; x <= c1[0]; ++x) grid[at(x, y, z)].push_back(static_cast<int>(t));
    }
    for (std::size_t e = 0; e < n; ++e) {
      const Vec3 c = centre(e);
      const double r = radius(e) + skin;
      bool outside = false;
      for (int d = 0; d < 3; ++d) outside = outside || c[d] + r < lo[d] || c[d] - r > hi[d];
      if (outside) continue;
      found.clear();
      for (int z = cell(c.z - r, 2); z <= cell(c.z + r, 2); ++z)
        for (int y = cell(c.y - r, 1); y <= cell(c.y + r, 1); ++y)
          for (int x = cell(c.x - r, 0); x <= cell(c.x + r, 0); ++x)
            for (const int t : grid[at(x, y, z)]) {
              TriangleFeature f;
              const auto& tri = m.triangles[t];
              const Vec3 q = closest_point_on_triangle(c, m.nodes[tri[0]], m.nodes[tri[1]], m.nodes[tri[2]], f);
              if (norm2(q - c) < r * r) found.push_back(t);
            }
      if (found.empty()) continue;
      std::sort(found.begin(), found.end());
      found.erase(std::unique(found.begin(), found.end()), found.end());
      entity_.push_back(static_cast<std::int32_t>(e));
      mesh_of_.push_back(static_cast<std::int32_t>(mi));
      cands_.insert(cands_.end(), found.begin(), found.end());
      cand_start_.push_back(static_cast<std::int32_t>(cands_.size()));
    }
  }
}

void MeshWallContacts::forces(ContactEntities& entities, std::vector<MeshWall>& meshes, ContactLanes& L,
                              const ContactCoefficients* sets, LawKind law, double dt, ReplicatedLoads& loads) {
  // Per (entity, mesh): the contacts after de-duplication (T11), each through the wall law with
  // the wall's velocity at the contact point; the reaction goes to the mesh (force, moment about
  // its origin), listed in `loads` for the sum in key order.
  for (auto& m : meshes) m.force = m.moment = Vec3{};
  hist_next_.clear();
  const bool sh = entities.shaped();
  std::vector<int> cands;
  for (std::size_t k = 0; k < entity_.size(); ++k) {
    const std::size_t e = entity_[k];
    MeshWall& m = meshes[mesh_of_[k]];
    const KernelGeometry ge = entities.geometry(e);
    const Vec3 c{ge.x, ge.y, ge.z};
    cands.assign(cands_.begin() + cand_start_[k], cands_.begin() + cand_start_[k + 1]);
    const auto contacts = sphere_mesh_contacts(c, ge.r, m.nodes, m.triangles, cands);
    if (contacts.empty()) continue;
    if (sh) entities.refresh_motion(e);
    const KernelMotion me = entities.motion(e);
    const std::int64_t ekey = entities.key(e);
    std::size_t nb = 0;
    std::uint64_t keys[ContactLanes::width];
    Vec3 points[ContactLanes::width];
    for (std::size_t j = 0; j < contacts.size() && nb < kMeshContactsPerSphere; ++j, ++nb) {
      const TriangleContact& tc = contacts[j];
      const Vec3 vw = m.velocity_at(tc.point);
      L.dx[nb] = tc.normal.x, L.dy[nb] = tc.normal.y, L.dz[nb] = tc.normal.z;
      L.ra[nb] = ge.r, L.rb[nb] = tc.overlap;
      L.vx[nb] = me.vx - vw.x, L.vy[nb] = me.vy - vw.y, L.vz[nb] = me.vz - vw.z;
      L.wx[nb] = me.wx * ge.r, L.wy[nb] = me.wy * ge.r, L.wz[nb] = me.wz * ge.r;
      keys[nb] = mesh_key(ekey, mesh_of_[k], static_cast<int>(j));
      points[nb] = tc.point;
      const std::array<double, 3> h = spring_or_zero(hist_, keys[nb]);
      L.hx[nb] = h[0], L.hy[nb] = h[1], L.hz[nb] = h[2];
      const ContactCoefficients& cs = sets[coefficient_[k]];
      L.set_coefficients(nb, cs);
    }
    if (nb == 0) continue;
    evaluate_wall_contacts(law, L, nb, dt);
    for (std::size_t j = 0; j < nb; ++j) {
      hist_next_[keys[j]] = {L.hx[j], L.hy[j], L.hz[j]};
      entities.add_wall_reaction(e, L, j);
      const Vec3 f{L.fx[j], L.fy[j], L.fz[j]};
      const Vec3 moment = cross(points[j] - m.origin, f);
      loads.add(static_cast<std::size_t>(mesh_of_[k]), -f, -moment);
    }
  }
  if (dt > 0) hist_.swap(hist_next_);
}

}  // namespace tessera
