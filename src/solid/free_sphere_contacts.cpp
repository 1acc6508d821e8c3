// SPDX-License-Identifier: MIT
#include "solid/free_sphere_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/errors.hpp"
#include "solid/triangle_contact.hpp"

namespace tessera {

void FreeSphereContacts::add(const FreeSphere& s) {
  if (spheres_.size() >= static_cast<std::size_t>(kMaxFreeSpheres))
    throw InputError(s.key, "", "at most " + std::to_string(kMaxFreeSpheres) + " free spheres");
  spheres_.push_back(s);
}

double FreeSphereContacts::displacement() const {
  double d = 0;
  for (const auto& s : spheres_) d = std::max(d, norm(s.x - s.x_build));
  return d;
}

void FreeSphereContacts::find(const ContactEntities& entities, double skin) {
  entity_.clear(), sphere_of_.clear();
  if (spheres_.empty()) return;
  const std::size_t n = entities.owned();
  for (std::size_t b = 0; b < spheres_.size(); ++b) {
    FreeSphere& s = spheres_[b];
    s.x_build = s.x;
    for (std::size_t e = 0; e < n; ++e) {
      const Vec3 c = entities.centre(e);
      const double reach = s.radius + entities.radius(e) + skin;
      if (norm2(c - s.x) < reach * reach) {
        entity_.push_back(static_cast<std::int32_t>(e));
        sphere_of_.push_back(static_cast<std::int32_t>(b));
      }
    }
  }
}

void FreeSphereContacts::grain_forces(ContactEntities& entities, ContactLanes& L, const ContactModel& model,
                                      double dt, std::size_t mesh_count, ReplicatedLoads& loads) {
  // Owned grains against the spheres, with the body-body law (d = x_grain - x_sphere).
  for (auto& s : spheres_) s.force = s.torque = Vec3{};
  grain_hist_next_.clear();
  const bool sh = entities.shaped();
  constexpr std::size_t W = ContactLanes::width;
  std::uint64_t keys[W];
  std::int32_t sphere[W];
  std::size_t entity[W];
  std::size_t nb = 0;
  auto flush = [&] {
    evaluate_contacts(model.law(), L, nb, dt, model.pair_table());
    for (std::size_t j = 0; j < nb; ++j) {
      grain_hist_next_[keys[j]] = {L.hx[j], L.hy[j], L.hz[j]};
      entities.add_wall_reaction(entity[j], L, j);
      const double rb = L.rb[j];
      loads.add(mesh_count + static_cast<std::size_t>(sphere[j]), Vec3{-L.fx[j], -L.fy[j], -L.fz[j]},
                Vec3{-L.nx[j] * rb, -L.ny[j] * rb, -L.nz[j] * rb});
    }
    nb = 0;
  };
  for (std::size_t k = 0; k < entity_.size(); ++k) {
    const std::size_t e = static_cast<std::size_t>(entity_[k]);
    const int b = sphere_of_[k];
    const FreeSphere& s = spheres_[static_cast<std::size_t>(b)];
    const KernelGeometry ge = entities.geometry(e);
    const double dx = ge.x - s.x.x, dy = ge.y - s.x.y, dz = ge.z - s.x.z;
    const double reach = ge.r + s.radius;
    if (dx * dx + dy * dy + dz * dz >= reach * reach) continue;
    if (sh) entities.refresh_motion(e);
    const KernelMotion me = entities.motion(e);
    const std::int64_t ekey = entities.key(e);
    keys[nb] = free_sphere_key(ekey, b);
    const std::array<double, 3> h = spring_or_zero(grain_hist_, keys[nb]);
    L.dx[nb] = dx, L.dy[nb] = dy, L.dz[nb] = dz;
    L.ra[nb] = ge.r, L.rb[nb] = s.radius;
    L.vx[nb] = me.vx - s.v.x, L.vy[nb] = me.vy - s.v.y, L.vz[nb] = me.vz - s.v.z;
    L.wx[nb] = me.wx * ge.r + s.omega.x * s.radius;
    L.wy[nb] = me.wy * ge.r + s.omega.y * s.radius;
    L.wz[nb] = me.wz * ge.r + s.omega.z * s.radius;
    L.hx[nb] = h[0], L.hy[nb] = h[1], L.hz[nb] = h[2];
    const double m = entities.mass(e);
    L.meff[nb] = m * s.mass / (m + s.mass);
    L.pair[nb] = entities.material(e) * model.material_count() + s.material;
    sphere[nb] = b, entity[nb] = e;
    if (++nb == W) flush();
  }
  if (nb) flush();
  if (dt > 0) grain_hist_.swap(grain_hist_next_);
}

void FreeSphereContacts::wall_forces(Walls& walls, ContactLanes& L, const ContactCoefficients* sets, LawKind law,
                                     double dt) {
  // Springs by (sphere, wall slot) and (sphere, mesh, ordinal).
  if (spheres_.empty()) return;
  const auto& prims = walls.primitives();
  auto& meshes = walls.meshes();
  const std::size_t per_sphere = prims.size() + meshes.size();
  wall_hist_next_.clear();
  for (std::size_t b = 0; b < spheres_.size(); ++b) {
    FreeSphere& s = spheres_[b];
    std::vector<Touch>& touches = touches_;
    touches.clear();
    s.touches_wall = false;
    for (std::size_t w = 0; w < prims.size(); ++w) {
      Vec3 n;
      const double delta = prims[w].overlap(s.x, s.radius, n);
      if (delta > 0) s.touches_wall = true;
      if (delta > 0)
        touches.push_back({wall_key(static_cast<std::int64_t>(b), static_cast<int>(w)), n, s.x - n * s.radius, delta,
                           wall_coefficient_[b * per_sphere + w], -1});
    }
    for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
      const MeshWall& m = meshes[mi];
      // Every triangle is a candidate (a club has a few dozen): ids 0 .. n - 1, made once per mesh.
      if (triangle_ids_.size() < meshes.size()) triangle_ids_.resize(meshes.size());
      std::vector<int>& all = triangle_ids_[mi];
      if (all.size() != m.triangles.size()) {
        all.resize(m.triangles.size());
        for (std::size_t t = 0; t < all.size(); ++t) all[t] = static_cast<int>(t);
      }
      const auto contacts = sphere_mesh_contacts(s.x, s.radius, m.nodes, m.triangles, all);
      for (std::size_t j = 0; j < contacts.size() && j < static_cast<std::size_t>(kMeshContactsPerSphere); ++j)
        touches.push_back({mesh_key(static_cast<std::int64_t>(b), static_cast<int>(mi), static_cast<int>(j)),
                           contacts[j].normal, contacts[j].point, contacts[j].overlap,
                           wall_coefficient_[b * per_sphere + prims.size() + mi], static_cast<int>(mi)});
    }
    for (std::size_t first = 0; first < touches.size(); first += ContactLanes::width) {
      const std::size_t nb = std::min(ContactLanes::width, touches.size() - first);
      for (std::size_t j = 0; j < nb; ++j) {
        const Touch& t = touches[first + j];
        const Vec3 vw = t.mesh >= 0 ? meshes[static_cast<std::size_t>(t.mesh)].velocity_at(t.point) : Vec3{};
        L.dx[j] = t.normal.x, L.dy[j] = t.normal.y, L.dz[j] = t.normal.z;
        L.ra[j] = s.radius, L.rb[j] = t.overlap;
        L.vx[j] = s.v.x - vw.x, L.vy[j] = s.v.y - vw.y, L.vz[j] = s.v.z - vw.z;
        L.wx[j] = s.omega.x * s.radius, L.wy[j] = s.omega.y * s.radius, L.wz[j] = s.omega.z * s.radius;
        const std::array<double, 3> h = spring_or_zero(wall_hist_, t.key);
        L.hx[j] = h[0], L.hy[j] = h[1], L.hz[j] = h[2];
        L.set_coefficients(j, sets[t.coefficient]);
      }
      evaluate_wall_contacts(law, L, nb, dt);
      for (std::size_t j = 0; j < nb; ++j) {
        const Touch& t = touches[first + j];
        wall_hist_next_[t.key] = {L.hx[j], L.hy[j], L.hz[j]};
        const Vec3 f{L.fx[j], L.fy[j], L.fz[j]};
        s.force += f;
        s.torque -= Vec3{L.nx[j], L.ny[j], L.nz[j]} * s.radius;
        if (t.mesh >= 0) {
          MeshWall& m = meshes[static_cast<std::size_t>(t.mesh)];
          m.force -= f;
          m.moment -= cross(t.point - m.origin, f);
        }
      }
    }
  }
  if (dt > 0) wall_hist_.swap(wall_hist_next_);
}

}  // namespace tessera
