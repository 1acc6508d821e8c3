// SPDX-License-Identifier: MIT
// The DEM's force stage (DemSolver::compute_forces): the contact law's coefficients per pair and
// per wall, then the pair, plane-wall, mesh-wall and free-sphere forces, accumulated through the lane
// kernel (contact_kernel.hpp) into the contact buffer (kernel_mirrors.hpp: 3D, or discs in plane
// mode); shaped bodies' element forces with their levers.
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/errors.hpp"
#include "solid/contact_kernel.hpp"
#include "solid/dem_solver.hpp"
#include "solid/triangle_contact.hpp"

namespace tessera {

void DemSolver::store_forces() {
  for (std::size_t i = 0; i < p_.owned; ++i) {
    const KernelForce fo = entities_.load(i);
    p_.f[3 * i] = fo.fx, p_.f[3 * i + 1] = fo.fy, p_.f[3 * i + 2] = fo.fz;
    p_.torque[3 * i] = fo.tx, p_.torque[3 * i + 1] = fo.ty, p_.torque[3 * i + 2] = fo.tz;
  }
}

void DemSolver::fill_coefficients() {
  // Walls, meshes: m* = m, R* = R (T7); free spheres with grains: m* and R* of the two.
  with_law(model_.law(), [&](auto law) { coefficients_.start<decltype(law)>(model_); });
  pairs_.fill_materials(entities_, model_);
  auto lookup = [&](int ma, int mb, double meff, double reff) { return coefficients_.find(ma, mb, meff, reff); };
  plane_walls_.fill_coefficients(entities_, walls_, lookup);
  mesh_walls_.fill_coefficients(entities_, walls_.meshes(), lookup);
  free_.fill_coefficients(walls_, lookup);
}

void DemSolver::compute_forces(bool update_history) {
  // dt = 0 leaves the springs unchanged (the initial forces at set-up).
  const double dt = update_history ? dt_ : 0.0;
  {
    auto t = timers_.scope("contact_forces");
    // Owned bodies' mirrors were packed by the integrator unless a rebuild moved them; shaped
    // bodies' elements were all placed.
    const std::size_t packed = shaped() ? entities_.size() : (owned_mirrors_current_ ? p_.owned : 0);
    pairs_.forces(entities_, packed, lanes_, model_, dt, update_history);
  }
  {
    auto t = timers_.scope("wall_forces");
    const ContactCoefficients* sets = coefficients_.data();
    const LawKind law = model_.law();
    plane_walls_.forces(entities_, p_, walls_, lanes_, sets, law, dt);
    auto& meshes = walls_.meshes();
    if (meshes.empty() && free_.empty()) return;
    loads_.clear();
    if (!meshes.empty()) mesh_walls_.forces(entities_, meshes, lanes_, sets, law, dt, loads_);
    if (!free_.empty()) free_.grain_forces(entities_, lanes_, model_, dt, meshes.size(), loads_);
    // A pivot and a free sphere need the whole load every step; other meshes only when reported.
    bool now = !free_.empty();
    for (const auto& m : meshes) now = now || m.motion == MeshWall::Motion::pivot;
    if (now) sum_mesh_loads();
    free_.wall_forces(walls_, lanes_, sets, law, dt);
  }
}

}  // namespace tessera
