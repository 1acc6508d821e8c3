// SPDX-License-Identifier: MIT
// Free spheres of the DEM (T17, free_spheres.hpp): DemSolver's members for them.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/errors.hpp"
#include "solid/dem_solver.hpp"
#include "solid/triangle_contact.hpp"

namespace tessera {

void DemSolver::add_free_sphere(const std::string& key, int material, double radius, const Vec3& x, const Vec3& v,
                                const Vec3& omega, double density) {
  if (free_.size() >= static_cast<std::size_t>(kMaxFreeSpheres))
    throw InputError(key, "", "at most " + std::to_string(kMaxFreeSpheres) + " free spheres");
  if (!(radius > 0)) throw InputError(key + ".radius", std::to_string(radius), "a positive radius");
  const double rho = density > 0 ? density : model_.materials()[material].density;
  FreeSphere s;
  s.key = key, s.material = material, s.radius = radius, s.x = x, s.v = v, s.omega = omega;
  if (plane_mode()) {
    const int n = settings_.plane_normal;
    s.x[n] = plane_position_, s.v[n] = 0;
    for (int k = 0; k < 3; ++k)
      if (k != n) s.omega[k] = 0;
    s.mass = rho * std::numbers::pi * radius * radius * settings_.plane_thickness;
    s.inertia = 0.5 * s.mass * radius * radius;
  } else {
    s.mass = rho * 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
    s.inertia = 0.4 * s.mass * radius * radius;
  }
  s.x_build = s.x;
  free_.push_back(s);
}

double DemSolver::free_sphere_displacement() const {
  double d = 0;
  for (const auto& s : free_) d = std::max(d, norm(s.x - s.x_build));
  return d;
}

void DemSolver::build_free_sphere_candidates() {
  free_entity_.clear(), free_of_.clear();
  if (free_.empty()) return;
  const std::size_t n = entities_.owned();
  for (std::size_t b = 0; b < free_.size(); ++b) {
    FreeSphere& s = free_[b];
    s.x_build = s.x;
    for (std::size_t e = 0; e < n; ++e) {
      const Vec3 c = entities_.centre(e);
      const double reach = s.radius + entities_.radius(e) + skin_;
      if (norm2(c - s.x) < reach * reach) {
        free_entity_.push_back(static_cast<std::int32_t>(e));
        free_of_.push_back(static_cast<std::int32_t>(b));
      }
    }
  }
}

void DemSolver::compute_free_sphere_forces(double dt) {
  // Owned grains against the spheres, with the body-body law (d = x_grain - x_sphere); the
  // reaction goes into mesh_loads_ with target meshes + sphere, summed by sum_mesh_loads.
  for (auto& s : free_) s.force = s.torque = Vec3{};
  const bool sh = shaped();
  ContactLanes& L = lanes_;
  const ContactCoefficients* sets = coefficient_sets_.data();
  const double target0 = static_cast<double>(walls_.meshes().size());
  constexpr std::size_t W = ContactLanes::width;
  std::uint64_t keys[W];
  std::int32_t sphere[W];
  std::size_t entity[W];
  std::size_t nb = 0;
  auto flush = [&] {
    evaluate_contacts(model_.law(), L, nb, dt);
    for (std::size_t j = 0; j < nb; ++j) {
      mesh_hist_next_[keys[j]] = {L.hx[j], L.hy[j], L.hz[j]};
      entities_.add_wall_reaction(entity[j], L, j);
      const double rb = L.rb[j];
      mesh_loads_.insert(
          mesh_loads_.end(),
          {static_cast<double>(keys[j] >> 32), static_cast<double>(keys[j] & 0xffffffffULL), target0 + sphere[j],
           -L.fx[j], -L.fy[j], -L.fz[j], -L.nx[j] * rb, -L.ny[j] * rb, -L.nz[j] * rb});
    }
    nb = 0;
  };
  for (std::size_t k = 0; k < free_entity_.size(); ++k) {
    const std::size_t e = static_cast<std::size_t>(free_entity_[k]);
    const int b = free_of_[k];
    const FreeSphere& s = free_[static_cast<std::size_t>(b)];
    const KernelGeometry ge = entities_.geometry(e);
    const double dx = ge.x - s.x.x, dy = ge.y - s.x.y, dz = ge.z - s.x.z;
    const double reach = ge.r + s.radius;
    if (dx * dx + dy * dy + dz * dz >= reach * reach) continue;
    if (sh) entities_.refresh_motion(e);
    const KernelMotion me = entities_.motion(e);
    const std::int64_t ekey = entities_.key(e);
    keys[nb] = free_sphere_key(ekey, b);
    const std::array<double, 3> h = spring_or_zero(mesh_hist_, keys[nb]);
    L.dx[nb] = dx, L.dy[nb] = dy, L.dz[nb] = dz;
    L.ra[nb] = ge.r, L.rb[nb] = s.radius;
    L.vx[nb] = me.vx - s.v.x, L.vy[nb] = me.vy - s.v.y, L.vz[nb] = me.vz - s.v.z;
    L.wx[nb] = me.wx * ge.r + s.omega.x * s.radius;
    L.wy[nb] = me.wy * ge.r + s.omega.y * s.radius;
    L.wz[nb] = me.wz * ge.r + s.omega.z * s.radius;
    L.hx[nb] = h[0], L.hy[nb] = h[1], L.hz[nb] = h[2];
    const ContactCoefficients& cs = sets[free_coefficient_[k]];
    L.set_coefficients(nb, cs);
    sphere[nb] = b, entity[nb] = e;
    if (++nb == W) flush();
  }
  if (nb) flush();
}

void DemSolver::compute_free_sphere_wall_forces(double dt) {
  // Every rank alike: each sphere against the wall planes and the mesh walls (wall law, m* and R*
  // of the sphere). Springs by (sphere, wall slot) and (sphere, mesh, ordinal).
  if (free_.empty()) return;
  const auto& prims = walls_.primitives();
  auto& meshes = walls_.meshes();
  const std::size_t per_sphere = prims.size() + meshes.size();
  ContactLanes& L = lanes_;
  const ContactCoefficients* sets = coefficient_sets_.data();
  free_hist_next_.clear();
  for (std::size_t b = 0; b < free_.size(); ++b) {
    FreeSphere& s = free_[b];
    std::vector<FreeTouch>& touches = free_touches_;
    touches.clear();
    s.touches_wall = false;
    for (std::size_t w = 0; w < prims.size(); ++w) {
      Vec3 n;
      const double delta = prims[w].overlap(s.x, s.radius, n);
      if (delta > 0) s.touches_wall = true;
      if (delta > 0)
        touches.push_back({wall_key(static_cast<std::int64_t>(b), static_cast<int>(w)), n, s.x - n * s.radius, delta,
                           free_wall_coefficient_[b * per_sphere + w], -1});
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
                           free_wall_coefficient_[b * per_sphere + prims.size() + mi], static_cast<int>(mi)});
    }
    for (std::size_t first = 0; first < touches.size(); first += ContactLanes::width) {
      const std::size_t nb = std::min(ContactLanes::width, touches.size() - first);
      for (std::size_t j = 0; j < nb; ++j) {
        const FreeTouch& t = touches[first + j];
        const Vec3 vw = t.mesh >= 0 ? meshes[static_cast<std::size_t>(t.mesh)].velocity_at(t.point) : Vec3{};
        L.dx[j] = t.normal.x, L.dy[j] = t.normal.y, L.dz[j] = t.normal.z;
        L.ra[j] = s.radius, L.rb[j] = t.overlap;
        L.vx[j] = s.v.x - vw.x, L.vy[j] = s.v.y - vw.y, L.vz[j] = s.v.z - vw.z;
        L.wx[j] = s.omega.x * s.radius, L.wy[j] = s.omega.y * s.radius, L.wz[j] = s.omega.z * s.radius;
        const std::array<double, 3> h = spring_or_zero(free_hist_, t.key);
        L.hx[j] = h[0], L.hy[j] = h[1], L.hz[j] = h[2];
        L.set_coefficients(j, sets[t.coefficient]);
      }
      evaluate_wall_contacts(model_.law(), L, nb, dt);
      for (std::size_t j = 0; j < nb; ++j) {
        const FreeTouch& t = touches[first + j];
        free_hist_next_[t.key] = {L.hx[j], L.hy[j], L.hz[j]};
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
  if (dt > 0) free_hist_.swap(free_hist_next_);
}

void DemSolver::kick_free_spheres(bool drift) {
  // Half-kick (and, after the first, the drift) of velocity Verlet, masked as the grains' are.
  const double h = 0.5 * dt_;
  const Vec3 vmask{velocity_mask_[0], velocity_mask_[1], velocity_mask_[2]};
  const Vec3 wmask{spin_mask_[0], spin_mask_[1], spin_mask_[2]};
  for (auto& s : free_) {
    s.v = hadamard(s.v + (s.force / s.mass + settings_.gravity) * h, vmask);
    s.omega = hadamard(s.omega + s.torque * (h / s.inertia), wmask);
    if (drift) s.x += s.v * dt_;
  }
}

}  // namespace tessera
