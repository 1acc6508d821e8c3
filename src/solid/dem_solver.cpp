// SPDX-License-Identifier: MIT
#include "solid/dem_solver.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "core/errors.hpp"
#include "core/exact_sum.hpp"
#include "solid/body_order.hpp"
#include "solid/contact_kernel.hpp"
#include "solid/triangle_contact.hpp"

namespace tessera {

DemSettings DemSettings::from_config(const ConfigNode& solid) {
  DemSettings s;
  s.gravity = solid.vec3("gravity", Dim::acceleration, s.gravity);
  // 0 (what the resolved case records when the key is absent) or no key: from the contact duration.
  if (const double dt = solid.real("time_step", Dim::time, Range::non_negative(), 0.0); dt > 0) s.time_step = dt;
  s.steps_per_contact = solid.real("steps_per_contact", Dim::none, Range::closed(5, 1e6), s.steps_per_contact);
  s.impact_velocity = solid.real("impact_velocity", Dim::velocity, Range::positive(), s.impact_velocity);
  // 0 (what the resolved case records when the key is absent) or no key: 0.5 r_min.
  if (const double skin = solid.real("neighbor_skin", Dim::length, Range::non_negative(), 0.0); skin > 0) s.skin = skin;
  s.relist = solid.flag("neighbor_relist", s.relist);
  if (const auto plane = solid.optional_section("plane")) {
    const std::string n = plane->choice("normal", {"x", "y", "z"});
    s.plane_normal = n[0] - 'x';
    s.plane_thickness = plane->real("thickness", Dim::length, Range::positive());
    if (plane->has("position")) s.plane_position = plane->real("position", Dim::length, Range::any());
    if (s.gravity[s.plane_normal] != 0)
      solid.fail("gravity", std::string("no component along the plane's normal (") + n + ") in plane mode");
  }
  return s;
}

DemSolver::DemSolver(const Decomposition& decomp, ContactModel model, Walls walls, DemSettings settings)
    : decomp_(decomp), model_(std::move(model)), walls_(std::move(walls)), settings_(settings), halo_(decomp) {
  p_.wall_slots = walls_.slots();
  entities_.configure(false, settings_.plane_normal);
  if (plane_mode()) {
    const int n = settings_.plane_normal;
    if (decomp.dims()[n] != 1)
      throw InputError("domain.process_grid", "",
                       std::string("one process along the plane's normal (") + "xyz"[n] + ") in plane mode");
    plane_position_ = settings_.plane_position.value_or(0.5 * (decomp.global_lo()[n] + decomp.global_hi()[n]));
    if (plane_position_ < decomp.global_lo()[n] || plane_position_ > decomp.global_hi()[n])
      throw InputError("solid.plane.position", std::to_string(plane_position_), "a position inside the domain");
    // Plane motion (T15): velocity in the plane, rotation about the normal only.
    for (int k = 0; k < 3; ++k) {
      velocity_mask_[k] = k == n ? 0.0 : 1.0;
      spin_mask_[k] = k == n ? 1.0 : 0.0;
    }
  }
}

void DemSolver::add_sphere(std::int64_t id, int material, double radius, const Vec3& x, const Vec3& v,
                           const Vec3& omega, double density) {
  if (id < 0 || id > kMaxBodyId) throw InputError("body id", std::to_string(id), "an id in [0, 2^32)");
  const double rho = density > 0 ? density : model_.materials()[material].density;
  if (plane_mode()) {
    // A disc of the plane's thickness, in the plane, moving in it (T15).
    Vec3 xp = x, vp = v, wp = omega;
    const int n = settings_.plane_normal;
    xp[n] = plane_position_;
    vp[n] = 0;
    for (int k = 0; k < 3; ++k)
      if (k != n) wp[k] = 0;
    if (!decomp_.owns(xp)) return;
    const double m = rho * std::numbers::pi * radius * radius * settings_.plane_thickness;
    p_.push_back(id, material, radius, m, 0.5 * m * radius * radius, xp, vp, wp);
    p_.owned = p_.size();
    return;
  }
  if (!decomp_.owns(x)) return;
  const double m = rho * 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
  p_.push_back(id, material, radius, m, 0.4 * m * radius * radius, x, v, omega);
  p_.owned = p_.size();
}

void DemSolver::set_shapes(std::vector<ShapeTemplate> templates) {
  if (p_.size() > 0) throw RunError("DemSolver::set_shapes must come before bodies are added");
  shapes_ = std::move(templates);
  key_stride_ = 1;
  for (const auto& t : shapes_) key_stride_ = std::max<std::int64_t>(key_stride_, std::ssize(t.spheres));
  // Templates with equal principal moments rotate like spheres (w += dt/2 T / I, q as for spheres):
  // free rotation of a spherical top is uniform, and a one-sphere template then moves bitwise as
  // the plain sphere.
  anisotropic_.assign(shapes_.size() + 1, 0);
  arm_.assign(shapes_.size() + 1, 0.0);
  for (std::size_t k = 0; k < shapes_.size(); ++k)
    for (const auto& c : shapes_[k].spheres) arm_[k + 1] = std::max(arm_[k + 1], norm(c));
  for (std::size_t k = 0; k < shapes_.size(); ++k) {
    const Vec3 I = shapes_[k].inertia_per_density;
    const double lo = std::min({I.x, I.y, I.z}), hi = std::max({I.x, I.y, I.z});
    anisotropic_[k + 1] = hi - lo > 1e-12 * hi;
  }
  entities_.configure(shaped(), settings_.plane_normal);
  if (shaped()) {
    halo_.forward_orientation = true;
    halo_.key_stride = key_stride_;
    p_.wall_slots = 0;  // wall histories are kept per contact sphere, by key
  }
}

void DemSolver::add_body(std::int64_t id, int material, int shape, const Vec3& x, const Quaternion& q, const Vec3& v,
                         const Vec3& omega, double density) {
  if (id < 0 || id > kMaxBodyId) throw InputError("body id", std::to_string(id), "an id in [0, 2^32)");
  if (shape < 1 || shape > std::ssize(shapes_))
    throw InputError("body shape", std::to_string(shape),
                     "a shape template index in [1, " + std::to_string(shapes_.size()) + "]");
  if (plane_mode())
    throw InputError("solid.plane", "", "sphere bodies (discs) only: shaped bodies are not available in plane mode");
  if (!decomp_.owns(x)) return;
  const ShapeTemplate& t = shapes_[shape - 1];
  const double rho = density > 0 ? density : model_.materials()[material].density;
  const double m = rho * t.volume;
  const std::size_t i = p_.push_back(id, material, t.bounding_radius, m, rho * t.inertia_per_density.z, x, v, omega);
  p_.shape[i] = shape;
  const double n = std::sqrt(q.norm2());
  p_.q[4 * i] = q.w / n, p_.q[4 * i + 1] = q.x / n, p_.q[4 * i + 2] = q.y / n, p_.q[4 * i + 3] = q.z / n;
  p_.owned = p_.size();
}

void DemSolver::add_free_sphere(const std::string& key, int material, double radius, const Vec3& x, const Vec3& v,
                                const Vec3& omega, double density) {
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
  free_.add(s);
}

void DemSolver::setup(bool fresh) {
  MPI_Comm comm = decomp_.comm();
  double local[3] = {1e300, 1e300, 0};  // min mass, min radius, -max radius
  std::vector<int> used(model_.material_count(), 0);
  for (std::size_t i = 0; i < p_.owned; ++i) {
    local[0] = std::min(local[0], p_.mass[i]);
    // Contact radius: the body's, or its template's contact spheres'.
    const int sh = p_.shape[i];
    local[1] = std::min(local[1], sh > 0 ? shapes_[sh - 1].sphere_radius : p_.radius[i]);
    local[2] = std::min(local[2], -p_.radius[i]);
    used[p_.material[i]] = 1;
  }
  double global[3];
  MPI_Allreduce(local, global, 3, MPI_DOUBLE, MPI_MIN, comm);
  MPI_Allreduce(MPI_IN_PLACE, used.data(), static_cast<int>(used.size()), MPI_INT, MPI_MAX, comm);
  long n_local = static_cast<long>(p_.owned), n = 0;
  MPI_Allreduce(&n_local, &n, 1, MPI_LONG, MPI_SUM, comm);
  if (n == 0) throw InputError("bodies", "0", "at least one body in the domain");
  if (walls_.slots() > kMaxWallSlots)
    throw InputError("solid.walls", std::to_string(walls_.slots()) + " wall planes",
                     "at most " + std::to_string(kMaxWallSlots) + " planes (a box counts 6)");
  if (walls_.meshes().size() > static_cast<std::size_t>(kMaxMeshWalls))
    throw InputError("solid.walls", std::to_string(walls_.meshes().size()) + " meshes",
                     "at most " + std::to_string(kMaxMeshWalls) + " mesh walls");
  if (n * key_stride_ >= kWallKeyBase)
    throw InputError("bodies", std::to_string(n),
                     "fewer than 2^32 / (contact spheres per body) bodies (element keys are 32-bit)");
  const double m_min = global[0], r_min = global[1];
  r_max_ = -global[2];

  std::vector<int> body_materials;
  for (int m = 0; m < model_.material_count(); ++m)
    if (used[m]) body_materials.push_back(m);
  for (int a : body_materials)
    for (int b : body_materials)
      if (!model_.has_pair(a, b))
        throw InputError("solid.contact.pairs", "", "an entry for every material pair in use");
  walls_.check_pairs(model_, body_materials);
  for (const auto& f : free_.spheres()) {
    for (int a : body_materials)
      if (!model_.has_pair(a, f.material))
        throw InputError("solid.contact.pairs", "",
                         "an entry for the free sphere '" + f.key + "' with every body material");
    walls_.check_pairs(model_, {f.material});
  }

  // Contact duration (T6): the shortest over the pairs in use, for the lightest body.
  t_contact_ = 1e300;
  for (int a : body_materials) {
    for (int b : body_materials)
      t_contact_ =
          std::min(t_contact_, model_.contact_duration(a, b, 0.5 * m_min, 0.5 * r_min, settings_.impact_velocity));
    for (const auto& w : walls_.primitives())
      t_contact_ =
          std::min(t_contact_, model_.contact_duration(a, w.material, m_min, r_min, settings_.impact_velocity));
    for (const auto& w : walls_.meshes())
      t_contact_ =
          std::min(t_contact_, model_.contact_duration(a, w.material, m_min, r_min, settings_.impact_velocity));
  }
  dt_ = settings_.time_step ? *settings_.time_step : t_contact_ / settings_.steps_per_contact;
  skin_ = settings_.skin ? *settings_.skin : 0.5 * r_min;
  check_subdomain_widths();

  if (fresh) assign_morton_order(p_, decomp_);
  rebuild();
  if (fresh) {
    // Forces of the initial state for the first half-kick; histories must not advance here.
    const std::vector<double> pair_history = pairs_.list().history, wall_history = p_.wall_history;
    compute_forces(false);
    store_forces();
    for (auto& m : walls_.meshes()) m.update_acceleration(settings_.gravity);
    pairs_.list().history = pair_history;
    p_.wall_history = wall_history;
  }
}

void DemSolver::check_subdomain_widths() const {
  // Ghosts come from face neighbours only: a sub-domain must be wider than the interaction reach.
  // Every rank sees the same grid and radii, so all stop together here.
  for (int d = 0; d < 3; ++d) {
    const auto& cuts = decomp_.cuts(d);
    for (std::size_t c = 0; c + 1 < cuts.size() && cuts.size() > 2; ++c)
      if (cuts[c + 1] - cuts[c] <= contact_reach())
        throw InputError("domain.process_grid", "",
                         "fewer ranks along axis " + std::to_string(d) + ": sub-domains " +
                             std::to_string(cuts[c + 1] - cuts[c]) + " m wide are narrower than the contact reach " +
                             std::to_string(contact_reach()) + " m (2 r_max + skin)");
  }
}

std::vector<WorkSample> DemSolver::work() const {
  std::vector<WorkSample> w(p_.owned);
  for (std::size_t i = 0; i < p_.owned; ++i) w[i] = {p_.pos(i), 1.0};
  const NeighborList& list = pairs_.list();
  for (std::size_t k = 0; k < list.size(); ++k)
    for (const std::size_t b : {entities_.body(list.first[k]), entities_.body(list.second[k])})
      if (b < p_.owned) w[b].weight += 1.0;
  return w;
}

void DemSolver::rebalance() {
  check_subdomain_widths();
  complete_step();  // no half-kick pending across the move
  long bodies[2] = {static_cast<long>(p_.owned), 0};
  migrate_until_settled_ = true;
  rebuild();
  migrate_until_settled_ = false;
  bodies[1] = static_cast<long>(p_.owned);
  MPI_Allreduce(MPI_IN_PLACE, bodies, 2, MPI_LONG, MPI_SUM, decomp_.comm());
  if (bodies[0] != bodies[1])
    throw RunError("rebalance at step " + std::to_string(steps_) + ": " + std::to_string(bodies[0]) +
                   " bodies before the cut planes moved, " + std::to_string(bodies[1]) + " after");
}

HistoryMap DemSolver::histories() const {
  HistoryMap h;
  pairs_.list().collect(h);
  plane_walls_.collect(h);
  for (const HistoryMap* springs : {&mesh_walls_.springs(), &free_.grain_springs()})
    for (const auto& [key, w] : *springs)
      if (w[0] != 0.0 || w[1] != 0.0 || w[2] != 0.0) h[key] = w;
  return h;
}

void DemSolver::rebuild() {
  owned_mirrors_current_ = false;
  fold_turns();  // the orientations travel with their bodies
  // Histories that must travel: restart entries, and the pairs of bodies about to leave this rank
  // (the new list takes everything else from the old one by a merge of sorted keys).
  HistoryMap histories = std::move(pending_);
  pending_.clear();
  if (decomp_.size() > 1) {
    std::vector<char> leaving(p_.size(), 0);
    bool any = false;
    for (std::size_t i = 0; i < p_.owned; ++i)
      if (!decomp_.owns(p_.pos(i))) leaving[i] = 1, any = true;
    // List entries hold entities (elements of shaped bodies, or bodies).
    if (any) {
      for (std::size_t k = 0; k < pairs_.list().size(); ++k) {
        const double* h = &pairs_.list().history[3 * k];
        if ((leaving[entities_.body(pairs_.list().first[k])] || leaving[entities_.body(pairs_.list().second[k])]) &&
            (h[0] != 0.0 || h[1] != 0.0 || h[2] != 0.0))
          histories[pairs_.list().keys[k]] = {h[0], h[1], h[2]};
      }
      plane_walls_.collect_leaving(entities_, leaving, histories);
      // Mesh-wall and free-sphere springs (few): all of them travel through the map; each rank
      // keeps its own below.
      for (const auto& [key, h] : mesh_walls_.springs()) histories.emplace(key, h);
      for (const auto& [key, h] : free_.grain_springs()) histories.emplace(key, h);
    }
  }
  {
    auto t = timers_.scope("migration");
    halo_.migrate(p_, histories);
    // After the cut planes moved a body may be several sub-domains from its owner: one face per
    // pass (rebalance only; in a step a body moves less than a sub-domain).
    while (migrate_until_settled_) {
      int foreign = 0;
      for (std::size_t i = 0; i < p_.owned && !foreign; ++i) foreign = !decomp_.owns(p_.pos(i));
      MPI_Allreduce(MPI_IN_PLACE, &foreign, 1, MPI_INT, MPI_MAX, decomp_.comm());
      if (!foreign) break;
      halo_.migrate(p_, histories);
    }
    sort_owned_by_order(p_);
  }
  for (const auto& [key, h] : histories)
    if (is_free_sphere_key(key))
      free_.adopt(key, h);
    else if (is_mesh_key(key))
      mesh_walls_.adopt(key, h);
  {
    auto t = timers_.scope("ghost_comm");
    halo_.build_ghosts(p_, r_max_ + skin_);
  }
  {
    auto t = timers_.scope("neighbor");
    if (shaped()) {
      entities_.layout(shapes_, key_stride_);
      element_r_max_ = 0;  // the elements' largest radius on this rank, till the next layout (T5b)
      for (const double r : entities_.element_radius()) element_r_max_ = std::max(element_r_max_, r);
      pairs_.list().build(list_elements(), skin_, histories);
      q_build_.assign(p_.q.begin(), p_.q.begin() + 4 * static_cast<std::ptrdiff_t>(p_.owned));
      x_list_.assign(p_.x.begin(), p_.x.begin() + 3 * static_cast<std::ptrdiff_t>(p_.size()));
      q_list_.assign(p_.q.begin(), p_.q.begin() + 4 * static_cast<std::ptrdiff_t>(p_.size()));
    } else {
      pairs_.list().build(p_, skin_, histories);
    }
    pairs_.start_list();
    x_build_.assign(p_.x.begin(), p_.x.begin() + 3 * static_cast<std::ptrdiff_t>(p_.owned));
    turn_.assign(plane_mode() ? p_.owned : 0, 0.0);
    inv_mass_.resize(p_.owned);
    inv_inertia_.resize(p_.owned);
    inertia3_.resize(3 * p_.owned);
    for (std::size_t i = 0; i < p_.owned; ++i) {
      inv_mass_[i] = 1.0 / p_.mass[i];
      // Shaped bodies: 0 here, so that the sphere update leaves their w alone (see rotate_shaped).
      inv_inertia_[i] = anisotropic(p_.shape[i]) ? 0.0 : 1.0 / p_.inertia[i];
      const int sh = p_.shape[i];
      for (int k = 0; k < 3; ++k)
        inertia3_[3 * i + k] =
            sh > 0 ? p_.mass[i] / shapes_[sh - 1].volume * shapes_[sh - 1].inertia_per_density[k] : p_.inertia[i];
    }
    plane_walls_.find(entities_, walls_, skin_, histories);
    x_moving_build_ = x_build_;
    find_moving_candidates();
    find_placed();
  }
}

static_assert(sizeof(KernelGeometry) == 4 * sizeof(double), "the list reads x, y, z of each mirror");

ContactElements DemSolver::list_elements() {
  ContactElements e;
  e.size = entities_.size();
  e.owned = entities_.owned();
  e.x = entities_.size() ? &entities_.geometry_mirrors()[0].x : nullptr;  // the elements' places now
  e.stride = sizeof(KernelGeometry) / sizeof(double);
  e.radius = entities_.element_radius().data();
  e.key = entities_.element_key().data();
  e.body = entities_.element_body().data();
  e.body_mass = p_.mass.data();
  // Theory T5b: a ghost element lies beyond the sub-box's face with a neighbour by more than
  // R_max + r_max + 3 s (R the bodies' reach, r the elements' radius) only where no owned element can
  // meet it before the next whole build.
  const double margin = r_max_ + element_r_max_ + 3.0 * skin_;
  const Vec3 lo = decomp_.sub_lo(), hi = decomp_.sub_hi();
  for (int d = 0; d < 3; ++d) {
    if (decomp_.neighbor(d, 0) != MPI_PROC_NULL) e.near_lo[d] = lo[d] - margin;
    if (decomp_.neighbor(d, 1) != MPI_PROC_NULL) e.near_hi[d] = hi[d] + margin;
  }
  return e;
}

bool DemSolver::relisting() const {
  return settings_.relist && shaped() && !plane_mode() && walls_.meshes().empty() && free_.empty();
}

double DemSolver::element_travel(std::size_t i, const double* x0, const double* q0) const {
  const double* x = &p_.x[3 * i];
  const double* q = &p_.q[4 * i];
  const double dx = x[0] - x0[0], dy = x[1] - x0[1], dz = x[2] - x0[2];
  const double c = q[0] * q0[0] + q[1] * q0[1] + q[2] * q0[2] + q[3] * q0[3];
  return std::sqrt(dx * dx + dy * dy + dz * dz) + 2.0 * arm_[p_.shape[i]] * std::sqrt(std::max(0.0, 1.0 - c * c));
}

// A stale body far from every cut cannot reach another rank's bodies, nor leave its own sub-box,
// before it is stale near one: its pairs are listed again here (theory T5a).
void DemSolver::relist_stale() {
  auto scope = timers_.scope("neighbor");
  const std::size_t n = p_.size();
  stale_.assign(n, 0);
  travel_.resize(n);
  bool any = false;  // the owned ones were found by needs_rebuild (relist_due_)
  for (std::size_t i = p_.owned; i < n; ++i) {
    travel_[i] = element_travel(i, &x_list_[3 * i], &q_list_[4 * i]);
    any = any || travel_[i] > 0.5 * skin_;
  }
  // All ranks relist at the sub-step where any of them must (needs_rebuild's reduction), so that
  // each waits at the next reduction for the slowest relist, not for the others' one after another.
  if (!any && !relist_due_) return;
  if (placing_listed_) entities_.place(shapes_, 0, p_.size());  // the list reads every element
  // Once one body is stale, every body past half of its allowance is listed with it: one merge of
  // the list for all that move, not one per sub-step (T5a).
  for (std::size_t i = 0; i < n; ++i) stale_[i] = travel_[i] > 0.25 * skin_;
  if (pairs_.list().relist(list_elements(), skin_, stale_, travel_)) stale_.assign(n, 1);  // all listed anew
  for (std::size_t i = 0; i < n; ++i)
    if (stale_[i]) {
      for (int d = 0; d < 3; ++d) x_list_[3 * i + d] = p_.x[3 * i + d];
      for (int d = 0; d < 4; ++d) q_list_[4 * i + d] = p_.q[4 * i + d];
    }
  pairs_.start_list();
  plane_walls_.refind(entities_, walls_, skin_, stale_);
  fill_coefficients();
  find_placed();
}

void DemSolver::place_elements(bool ghosts) {
  if (!placing_listed_) {
    ghosts ? entities_.place(shapes_, p_.owned, p_.size()) : entities_.place(shapes_, 0, p_.owned);
    return;
  }
  const std::int32_t* e = placed_.data();
  ghosts ? entities_.place_listed(shapes_, e + placed_owned_, e + placed_.size())
         : entities_.place_listed(shapes_, e, e + placed_owned_);
}

void DemSolver::find_placed() {
  placing_listed_ = shaped() && relisting();
  if (!placing_listed_) return;
  const std::size_t n = entities_.size();
  std::vector<char>& in = placed_mark_;
  in.assign(n, 0);
  const auto& list = pairs_.list();
  for (std::size_t k = 0; k < list.size(); ++k) in[static_cast<std::size_t>(list.first[k])] = in[static_cast<std::size_t>(list.second[k])] = 1;
  for (const auto e : plane_walls_.entities()) in[static_cast<std::size_t>(e)] = 1;
  placed_.clear();
  placed_owned_ = 0;
  for (std::size_t e = 0; e < n; ++e)
    if (in[e]) {
      placed_.push_back(static_cast<std::int32_t>(e));
      if (e < entities_.owned()) ++placed_owned_;
    }
  // Where most elements are listed (a settled bed), placing them all in one pass costs less than
  // picking them out, and a relist need not place the rest (a rank's own choice: the same bits).
  placing_listed_ = 2 * placed_.size() < n;
}

bool DemSolver::needs_rebuild() {
  // [0]: squared largest displacement since the list build; [1]: since the moving walls' candidates
  // were last found (sphere bodies; the same as [0] for shaped ones).
  // [2]: 1 where an owned body is past s/2 since its own listing (T5a's trigger, taken by all ranks).
  double max2[3] = {0, 0, 0};
  const bool moving = !walls_.meshes().empty() || !free_.empty();
  {
    auto scope = timers_.scope("neighbor");  // the displacement check is part of the list's cost
    if (relisting()) {
      // The ghosts and the owners stay right while no body has left its sub-domain by skin/2 and
      // none has come within r + r_max + skin/2 of a face it was not copied across (Halo's rule at
      // the build): the stale ones are relisted where they are (theory T5a).
      const Vec3 lo = decomp_.sub_lo(), hi = decomp_.sub_hi();
      const double half = 0.5 * skin_;
      for (std::size_t i = 0; i < p_.owned && max2[0] == 0; ++i)
        for (int d = 0; d < 3; ++d) {
          if (decomp_.dims()[d] == 1) continue;
          const double x = p_.x[3 * i + d], x0 = x_build_[3 * i + d];
          const double copied = p_.radius[i] + r_max_ + skin_, near = copied - half;
          if (decomp_.neighbor(d, 0) != MPI_PROC_NULL &&
              (x < lo[d] - half || (!(x0 < lo[d] + copied) && x < lo[d] + near)))
            max2[0] = skin_ * skin_;
          if (decomp_.neighbor(d, 1) != MPI_PROC_NULL &&
              (x > hi[d] + half || (!(x0 >= hi[d] - copied) && x >= hi[d] - near)))
            max2[0] = skin_ * skin_;
        }
      max2[1] = max2[0];
      // The owned bodies' travels since their listings, kept for relist_stale (they do not move
      // again before it; the ghosts' places come with the forward exchange after this).
      travel_.resize(p_.size());
      for (std::size_t i = 0; i < p_.owned && 3 * i < x_list_.size(); ++i) {
        travel_[i] = element_travel(i, &x_list_[3 * i], &q_list_[4 * i]);
        if (travel_[i] > half) max2[2] = 1;
      }
    } else if (shaped()) {
      // A contact sphere at distance c from its body's centre has moved at most
      // |dx| + 2 c sin(theta/2), theta the body's rotation since the build (cos(theta/2) = |q . q0|).
      for (std::size_t i = 0; i < p_.owned; ++i) {
        const double d = element_travel(i, &x_build_[3 * i], &q_build_[4 * i]);
        max2[0] = std::max(max2[0], d * d);
      }
      max2[1] = max2[0];
    } else {
      max2[0] = moved2_[0], max2[1] = moved2_[1];  // sphere bodies: found by integrate_first
    }
  }
  auto t = timers_.scope("reduction");
  MPI_Allreduce(MPI_IN_PLACE, max2, 3, MPI_DOUBLE, MPI_MAX, decomp_.comm());
  relist_due_ = max2[2] > 0;
  refresh_moving_ = false;
  if (!moving) return max2[0] > 0.25 * skin_ * skin_;
  // Moving meshes and free spheres: a body and a wall approach each other by at most the sum of
  // their displacements (the same on every rank). The pair list is rebuilt only when the bodies
  // moved skin/2; when only a wall did, its candidate lists are found again (sphere bodies) or
  // everything is rebuilt (shaped bodies).
  const bool walls_moved = std::sqrt(max2[1]) + std::max(mesh_walls_.displacement(walls_.meshes()), free_.displacement()) > 0.5 * skin_;
  if (max2[0] > 0.25 * skin_ * skin_ || (walls_moved && shaped())) return true;
  refresh_moving_ = walls_moved;
  return false;
}

void DemSolver::refresh_moving_candidates() {
  auto t = timers_.scope("neighbor");
  x_moving_build_.assign(p_.x.begin(), p_.x.begin() + 3 * static_cast<std::ptrdiff_t>(p_.owned));
  find_moving_candidates();
}

void DemSolver::find_moving_candidates() {
  mesh_walls_.find(entities_, walls_.meshes(), skin_);
  free_.find(entities_, skin_);
  fill_coefficients();
}

void DemSolver::step(bool defer_kick) {
  first_half_kick_and_drift();
  update_neighbours();
  compute_forces(true);
  second_half_kick(defer_kick);
  time_ += dt_;
  ++steps_;
  if (!(std::isfinite(p_.owned ? p_.x[0] : 0.0)))
    throw RunError("non-finite body position at step " + std::to_string(steps_) +
                   ": the time step is too large for the contact stiffness");
}

void DemSolver::first_half_kick_and_drift() {
  if (plane_walls_.tracking_impulse()) plane_walls_.add_half_impulse(dt_);  // the kick's wall forces
  auto t = timers_.scope("integrate");
  integrate_first();
  kick_free_spheres(true);
  kick_pivots(false);
  if (shaped()) place_elements(false);
  for (auto& m : walls_.meshes()) m.advance(dt_);
}

void DemSolver::update_neighbours() {
  if (needs_rebuild()) {
    rebuild();
    return;
  }
  {
    auto t = timers_.scope("ghost_comm");
    halo_.forward(p_);
    if (shaped()) place_elements(true);
  }
  if (relisting()) relist_stale();
  if (refresh_moving_) refresh_moving_candidates();
}

void DemSolver::second_half_kick(bool defer) {
  if (plane_walls_.tracking_impulse()) plane_walls_.add_half_impulse(dt_);
  auto t = timers_.scope("integrate");
  if (defer && !shaped())
    kick_pending_ = true;
  else
    integrate_second();
  kick_free_spheres(false);
  kick_pivots(true);
}

}  // namespace tessera
