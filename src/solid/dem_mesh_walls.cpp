// SPDX-License-Identifier: MIT
// Triangle-mesh walls inside the DEM step (T14, mesh_walls.hpp): candidate triangles of each
// (element, mesh) pair within reach at a rebuild, the contacts' forces each step (face, edge or
// vertex, counted once, T11), and the loads on the meshes summed over all ranks in key order (a
// pivot's equation of motion needs the whole load every step).
#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/all_gather.hpp"
#include "solid/contact_kernel.hpp"
#include "solid/dem_solver.hpp"
#include "solid/triangle_contact.hpp"

namespace tessera {

double DemSolver::mesh_displacement() const {
  double d2 = 0;
  const auto& meshes = walls_.meshes();
  for (std::size_t m = 0; m < meshes.size() && m < mesh_nodes_build_.size(); ++m)
    for (std::size_t k = 0; k < meshes[m].nodes.size(); ++k)
      d2 = std::max(d2, norm2(meshes[m].nodes[k] - mesh_nodes_build_[m][k]));
  return std::sqrt(d2);
}

void DemSolver::build_mesh_candidates() {
  // Each owned entity (body, or contact sphere of a shaped body) against each mesh: the triangles
  // within its radius + skin, found through a grid of the triangles' bounding boxes.
  mesh_entity_.clear(), mesh_of_.clear(), mesh_cands_.clear();
  mesh_cand_start_.assign(1, 0);
  const auto& meshes = walls_.meshes();
  mesh_nodes_build_.resize(meshes.size());
  if (meshes.empty()) return;
  const std::size_t n = entities_.owned();
  auto centre = [&](std::size_t e) { return entities_.centre(e); };
  auto radius = [&](std::size_t e) { return entities_.radius(e); };
  double r_max = 0;
  for (std::size_t e = 0; e < n; ++e) r_max = std::max(r_max, radius(e));
  std::vector<int> found;
  for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
    const MeshWall& m = meshes[mi];
    mesh_nodes_build_[mi] = m.nodes;
    Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    double edge = 0;
    for (const auto& t : m.triangles)
      for (int a = 0; a < 3; ++a) {
        const Vec3& v = m.nodes[t[a]];
        for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], v[d]), hi[d] = std::max(hi[d], v[d]);
        edge = std::max(edge, norm(v - m.nodes[t[(a + 1) % 3]]));
      }
    const double reach = r_max + skin_;
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
      const double r = radius(e) + skin_;
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
      mesh_entity_.push_back(static_cast<std::int32_t>(e));
      mesh_of_.push_back(static_cast<std::int32_t>(mi));
      mesh_cands_.insert(mesh_cands_.end(), found.begin(), found.end());
      mesh_cand_start_.push_back(static_cast<std::int32_t>(mesh_cands_.size()));
    }
  }
}

void DemSolver::compute_mesh_forces(double dt) {
  // Per (entity, mesh): the contacts after de-duplication (T11), each through the wall law with
  // the wall's velocity at the contact point; the reaction goes to the mesh (force, moment about
  // its origin). Tangential springs are kept by (element key, mesh, contact ordinal): a sphere
  // rolling over a flat mesh keeps its spring across triangle edges.
  auto& meshes = walls_.meshes();
  for (auto& m : meshes) m.force = m.moment = Vec3{};
  const bool sh = shaped();
  ContactLanes& L = lanes_;
  const ContactCoefficients* sets = coefficient_sets_.data();
  std::vector<int> cands;
  // The load on each mesh is summed over all contacts in key order, on every rank: the same bits
  // whatever the decomposition (pivot dynamics stay rank-count independent).
  std::vector<double>& loads = mesh_loads_;  // per contact: key (2 x 32 bits), mesh, force, moment
  for (std::size_t k = 0; k < mesh_entity_.size(); ++k) {
    const std::size_t e = mesh_entity_[k];
    MeshWall& m = meshes[mesh_of_[k]];
    const KernelGeometry ge = entities_.geometry(e);
    const Vec3 c{ge.x, ge.y, ge.z};
    cands.assign(mesh_cands_.begin() + mesh_cand_start_[k], mesh_cands_.begin() + mesh_cand_start_[k + 1]);
    const auto contacts = sphere_mesh_contacts(c, ge.r, m.nodes, m.triangles, cands);
    if (contacts.empty()) continue;
    if (sh) entities_.refresh_motion(e);
    const KernelMotion me = entities_.motion(e);
    const std::int64_t ekey = entities_.key(e);
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
      const std::array<double, 3> h = spring_or_zero(mesh_hist_, keys[nb]);
      L.hx[nb] = h[0], L.hy[nb] = h[1], L.hz[nb] = h[2];
      const ContactCoefficients& cs = sets[mesh_coefficient_[k]];
      L.set_coefficients(nb, cs);
    }
    if (nb == 0) continue;
    evaluate_wall_contacts(model_.law(), L, nb, dt);
    for (std::size_t j = 0; j < nb; ++j) {
      mesh_hist_next_[keys[j]] = {L.hx[j], L.hy[j], L.hz[j]};
      entities_.add_wall_reaction(e, L, j);
      const Vec3 f{L.fx[j], L.fy[j], L.fz[j]};
      const Vec3 moment = cross(points[j] - m.origin, f);
      loads.insert(loads.end(), {static_cast<double>(keys[j] >> 32), static_cast<double>(keys[j] & 0xffffffffULL),
                                 static_cast<double>(mesh_of_[k]), -f.x, -f.y, -f.z, -moment.x, -moment.y, -moment.z});
    }
  }
}

void DemSolver::sum_mesh_loads() {
  // Every rank gets the load on each mesh, summed over all contacts in key order.
  if (!mesh_loads_pending_) return;
  mesh_loads_pending_ = false;
  auto& meshes = walls_.meshes();
  constexpr int stride = 9;
  const std::vector<double> all = all_gather_concat(decomp_.comm(), mesh_loads_);
  const std::size_t n = all.size() / stride;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return all[a * stride] != all[b * stride] ? all[a * stride] < all[b * stride]
                                              : all[a * stride + 1] < all[b * stride + 1];
  });
  for (const auto c : order) {
    const double* r = &all[c * stride];
    const auto target = static_cast<std::size_t>(r[2]);
    if (target < meshes.size()) {
      MeshWall& m = meshes[target];
      m.force += Vec3{r[3], r[4], r[5]};
      m.moment += Vec3{r[6], r[7], r[8]};
    } else {  // a free sphere: moment about its centre
      FreeSphere& s = free_[target - meshes.size()];
      s.force += Vec3{r[3], r[4], r[5]};
      s.torque += Vec3{r[6], r[7], r[8]};
    }
  }
}

}  // namespace tessera
