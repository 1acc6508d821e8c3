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
  with_law(model_.law(), [&](auto law) { fill_pair_coefficients<decltype(law)>(); });
}

template <class Law>
void DemSolver::fill_pair_coefficients() {
  struct Key {
    std::int32_t ma, mb;
    double meff, reff;
    bool operator==(const Key& o) const { return ma == o.ma && mb == o.mb && meff == o.meff && reff == o.reff; }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = std::bit_cast<std::uint64_t>(k.meff) * 0x9E3779B97F4A7C15ULL;
      h ^= std::bit_cast<std::uint64_t>(k.reff) + 0x94D049BB133111EBULL + (h << 6) + (h >> 2);
      return h ^ (static_cast<std::uint64_t>(k.ma) << 32 | static_cast<std::uint32_t>(k.mb));
    }
  };
  std::unordered_map<Key, std::int32_t, KeyHash> index;
  coefficient_sets_.clear();
  Key last{-1, -1, 0, 0};
  std::int32_t last_index = -1;
  auto lookup = [&](const Key& key) {
    if (key == last) return last_index;  // neighbours in a list are often alike: skip the hash
    const auto [it, added] = index.emplace(key, static_cast<std::int32_t>(coefficient_sets_.size()));
    if (added)
      coefficient_sets_.push_back(
          ContactCoefficients::of<Law>(Law::coefficients(model_.pair(key.ma, key.mb), key.meff, key.reff)));
    last = key, last_index = it->second;
    return it->second;
  };
  // Entries hold entities: their radius, and their body's material and mass.
  auto radius = [&](std::size_t e) { return entities_.radius(e); };
  auto body = [&](std::size_t e) { return entities_.body(e); };
  pair_coefficient_.resize(list_.size());
  // Grains of many sizes make nearly every pair's (m*, R*) distinct: once the first 256 pairs show
  // that (more than half of them new sets), the rest get their own sets without the hash map.
  constexpr std::size_t probe = 256;
  bool shared = true;
  for (std::size_t k = 0; k < list_.size(); ++k) {
    const std::size_t a = list_.first[k], b = list_.second[k];
    const double ra = radius(a), rb = radius(b);
    const Key key{p_.material[body(a)], p_.material[body(b)], list_.meff[k], ra * rb / (ra + rb)};
    if (shared) {
      pair_coefficient_[k] = lookup(key);
      if (k + 1 == probe && 2 * coefficient_sets_.size() > probe) shared = false;
    } else {
      pair_coefficient_[k] = static_cast<std::int32_t>(coefficient_sets_.size());
      coefficient_sets_.push_back(
          ContactCoefficients::of<Law>(Law::coefficients(model_.pair(key.ma, key.mb), key.meff, key.reff)));
    }
  }
  // Walls: m* = m, R* = R (T7).
  const auto& prims = walls_.primitives();
  plane_walls_.fill_coefficients(entities_, walls_, [&](int ma, int mb, double meff, double reff) {
    return lookup({ma, mb, meff, reff});
  });
  const auto& meshes = walls_.meshes();
  mesh_coefficient_.resize(mesh_entity_.size());
  for (std::size_t k = 0; k < mesh_entity_.size(); ++k) {
    const std::size_t e = mesh_entity_[k];
    mesh_coefficient_[k] = lookup({p_.material[body(e)], meshes[mesh_of_[k]].material, p_.mass[body(e)], radius(e)});
  }
  // Free spheres: with grains as a body pair (m*, R* of the two), with walls and meshes as a wall.
  free_coefficient_.resize(free_entity_.size());
  for (std::size_t k = 0; k < free_entity_.size(); ++k) {
    const std::size_t e = free_entity_[k];
    const FreeSphere& s = free_[free_of_[k]];
    const double m = p_.mass[body(e)], r = radius(e);
    free_coefficient_[k] =
        lookup({p_.material[body(e)], s.material, m * s.mass / (m + s.mass), r * s.radius / (r + s.radius)});
  }
  free_wall_coefficient_.clear();
  for (const auto& s : free_) {
    for (const auto& w : prims) free_wall_coefficient_.push_back(lookup({s.material, w.material, s.mass, s.radius}));
    for (const auto& m : meshes) free_wall_coefficient_.push_back(lookup({s.material, m.material, s.mass, s.radius}));
  }
}

void DemSolver::compute_forces(bool update_history) {
  // dt = 0 leaves the springs unchanged (the initial forces at set-up).
  const double dt = update_history ? dt_ : 0.0;
  {
    auto t = timers_.scope("contact_forces");
    compute_pair_forces(dt, update_history);
  }
  {
    auto t = timers_.scope("wall_forces");
    plane_walls_.forces(entities_, p_, walls_, lanes_, coefficient_sets_.data(), model_.law(), dt);
    const auto& meshes = walls_.meshes();
    if (meshes.empty() && free_.empty()) return;
    mesh_hist_next_.clear();
    mesh_loads_.clear();
    if (!meshes.empty()) compute_mesh_forces(dt);
    if (!free_.empty()) compute_free_sphere_forces(dt);
    if (dt > 0) mesh_hist_.swap(mesh_hist_next_);
    // A pivot and a free sphere need the whole load every step; other meshes only when reported.
    mesh_loads_pending_ = true;
    bool now = !free_.empty();
    for (const auto& m : meshes) now = now || m.motion == MeshWall::Motion::pivot;
    if (now) sum_mesh_loads();
    compute_free_sphere_wall_forces(dt);
  }
}

// The pair loop's access to one mirror layout: packing a body's mirror, pass 1's overlap test, the
// partner's prefetches, the gather of a pair into a lane and the accumulation of its force.
struct DemSolver::SphereMirrors {  // 3D mirrors per element (spheres, shaped bodies' elements)
  const ParticleStore& p;
  const ContactEntities& entities;
  KernelGeometry* g;
  KernelMotion* m;
  KernelForce* out;
  bool sh;
  void pack(std::size_t i) {
    const double* x = &p.x[3 * i];
    const double* v = &p.v[3 * i];
    const double* w = &p.omega[3 * i];
    g[i] = {x[0], x[1], x[2], p.radius[i]};
    m[i] = {v[0], v[1], v[2], w[0], w[1], w[2]};
  }
  bool touching(std::size_t a, std::size_t b) const {
    const KernelGeometry &ga = g[a], &gb = g[b];
    const double dx = ga.x - gb.x, dy = ga.y - gb.y, dz = ga.z - gb.z, rsum = ga.r + gb.r;
    return dx * dx + dy * dy + dz * dz < rsum * rsum;
  }
  void prefetch_geometry(std::size_t b) const { __builtin_prefetch(&g[b]); }
  void prefetch_partner(std::size_t b) const {
    __builtin_prefetch(&g[b]);
    __builtin_prefetch(&m[b]);
    __builtin_prefetch(&out[b], 1);
  }
  void gather(ContactLanes& L, std::size_t j, std::size_t a, std::size_t b) const {
    const KernelGeometry &ga = g[a], &gb = g[b];
    const KernelMotion &ma = m[a], &mb = m[b];
    L.dx[j] = ga.x - gb.x, L.dy[j] = ga.y - gb.y, L.dz[j] = ga.z - gb.z;
    L.ra[j] = ga.r, L.rb[j] = gb.r;
    L.vx[j] = ma.vx - mb.vx, L.vy[j] = ma.vy - mb.vy, L.vz[j] = ma.vz - mb.vz;
    L.wx[j] = ma.wx * ga.r + mb.wx * gb.r;
    L.wy[j] = ma.wy * ga.r + mb.wy * gb.r;
    L.wz[j] = ma.wz * ga.r + mb.wz * gb.r;
  }
  void accumulate(const ContactLanes& L, std::size_t j, std::size_t ea, std::size_t eb) {
    const std::size_t a = sh ? entities.body(ea) : ea;
    const std::size_t b = sh ? entities.body(eb) : eb;
    KernelForce &fa = out[a], &fb = out[b];
    fa.fx += L.fx[j], fa.fy += L.fy[j], fa.fz += L.fz[j];
    fb.fx -= L.fx[j], fb.fy -= L.fy[j], fb.fz -= L.fz[j];
    fa.tx -= L.nx[j] * L.ra[j], fa.ty -= L.ny[j] * L.ra[j], fa.tz -= L.nz[j] * L.ra[j];
    fb.tx -= L.nx[j] * L.rb[j], fb.ty -= L.ny[j] * L.rb[j], fb.tz -= L.nz[j] * L.rb[j];
    if (sh) {
      entities.add_lever(fa, g[ea], a, L.fx[j], L.fy[j], L.fz[j]);
      entities.add_lever(fb, g[eb], b, -L.fx[j], -L.fy[j], -L.fz[j]);
    }
  }
};

template <int N>
struct DemSolver::DiscMirrors {  // plane mode, normal along axis N (kernel_mirrors.hpp)
  static constexpr int U = plane_u(N), V = plane_v(N);
  const ParticleStore& p;
  DiscMirror* g;
  DiscForce* out;
  void pack(std::size_t i) {
    const double* x = &p.x[3 * i];
    const double* v = &p.v[3 * i];
    g[i] = {x[U], x[V], p.radius[i], v[U], v[V], p.omega[3 * i + N]};
  }
  bool touching(std::size_t a, std::size_t b) const {
    const DiscMirror &ga = g[a], &gb = g[b];
    const double du = ga.u - gb.u, dv = ga.v - gb.v, rsum = ga.r + gb.r;
    return du * du + dv * dv < rsum * rsum;
  }
  void prefetch_geometry(std::size_t b) const { __builtin_prefetch(&g[b]); }
  void prefetch_partner(std::size_t b) const {
    __builtin_prefetch(&g[b]);
    __builtin_prefetch(&out[b], 1);
  }
  void gather(ContactLanes& L, std::size_t j, std::size_t a, std::size_t b) const {
    const DiscMirror &ga = g[a], &gb = g[b];
    double* d[3] = {L.dx, L.dy, L.dz};
    double* v[3] = {L.vx, L.vy, L.vz};
    double* w[3] = {L.wx, L.wy, L.wz};
    d[U][j] = ga.u - gb.u, d[V][j] = ga.v - gb.v, d[N][j] = 0.0;
    L.ra[j] = ga.r, L.rb[j] = gb.r;
    v[U][j] = ga.vu - gb.vu, v[V][j] = ga.vv - gb.vv, v[N][j] = 0.0;
    w[U][j] = 0.0, w[V][j] = 0.0, w[N][j] = ga.wn * ga.r + gb.wn * gb.r;
  }
  void accumulate(const ContactLanes& L, std::size_t j, std::size_t a, std::size_t b) {
    const double* f[3] = {L.fx, L.fy, L.fz};
    const double* nf[3] = {L.nx, L.ny, L.nz};
    DiscForce &fa = out[a], &fb = out[b];
    fa.fu += f[U][j], fa.fv += f[V][j];
    fb.fu -= f[U][j], fb.fv -= f[V][j];
    fa.tn -= nf[N][j] * L.ra[j];
    fb.tn -= nf[N][j] * L.rb[j];
  }
};

void DemSolver::compute_pair_forces(double dt, bool update_history) {
  entities_.start_forces();
  if (!entities_.discs()) {
    SphereMirrors view{p_, entities_, entities_.geometry_mirrors().data(), entities_.motion_mirrors().data(),
                       entities_.forces().data(), shaped()};
    pair_forces(view, dt, update_history);
    return;
  }
  DiscMirror* g = entities_.disc_mirrors().data();
  DiscForce* f = entities_.disc_forces().data();
  auto run = [&](auto view) { pair_forces(view, dt, update_history); };
  switch (plane_normal()) {
    case 0: run(DiscMirrors<0>{p_, g, f}); break;
    case 1: run(DiscMirrors<1>{p_, g, f}); break;
    default: run(DiscMirrors<2>{p_, g, f}); break;
  }
}

template <class Mirrors>
void DemSolver::pair_forces(Mirrors& view, double dt, bool update_history) {
  const std::size_t n = entities_.size();
  const std::size_t np = list_.size();
  const std::int32_t* first = list_.first.data();
  const std::int32_t* second = list_.second.data();
  double* hist = list_.history.data();
  // Owned bodies were packed by integrate_first unless a rebuild moved them; ghosts always here.
  // (Shaped mode: every element was packed by update_elements.)
  for (std::size_t i = shaped() ? n : (owned_mirrors_current_ ? p_.owned : 0); i < n; ++i) view.pack(i);
  // Pass 1, branch-free: which listed pairs touch (about half of them in a dense bed, at random,
  // which a branch would mispredict). The compacted list keeps the canonical order.
  // Contacts that opened since the last evaluation lose their history (T3): a pair that touched then
  // (was_touching_) and does not now. Rare, so the branch is predicted.
  touching_.resize(np);
  was_touching_.resize(np, 0);
  std::uint8_t* was = was_touching_.data();
  std::size_t nt = 0;
  // Prefetch distances: partners are scattered over ~1000 bodies, and a large bed's mirrors come
  // from memory. Pass 1 spends a few ns a pair, so it looks further ahead than pass 2.
  constexpr std::size_t ahead = 16, ahead1 = 64;
  for (std::size_t k = 0; k < np; ++k) {
    if (k + ahead1 < np) view.prefetch_geometry(second[k + ahead1]);
    touching_[nt] = static_cast<std::int32_t>(k);
    const bool touch = view.touching(first[k], second[k]);
    nt += touch ? 1 : 0;
    if (update_history) {
      if (was[k] && !touch) hist[3 * k] = hist[3 * k + 1] = hist[3 * k + 2] = 0.0;
      was[k] = touch ? 1 : 0;
    }
  }
  touching_.resize(nt);
  if (shaped())
    for (const auto k : touching_) entities_.refresh_motion(first[k]), entities_.refresh_motion(second[k]);
  // Pass 2, in blocks: gather the pairs' data into lanes, evaluate the law on all lanes
  // (vectorised, contact_kernel.cpp), then accumulate forces in canonical order.
  constexpr std::size_t B = ContactLanes::width;
  ContactLanes& L = lanes_;
  const ContactCoefficients* sets = coefficient_sets_.data();
  const std::int32_t* pc = pair_coefficient_.data();
  for (std::size_t s = 0; s < nt; s += B) {
    const std::size_t nb = std::min(B, nt - s);
    for (std::size_t j = 0; j < nb; ++j) {
      if (s + j + ahead < nt) {
        // The partner's lines (pass 1 read its geometry long ago: a large bed's mirrors leave the
        // cache in between), the pair's history and its coefficient set.
        const std::size_t kk = static_cast<std::size_t>(touching_[s + j + ahead]);
        view.prefetch_partner(second[kk]);
        __builtin_prefetch(&hist[3 * kk], 1);
        __builtin_prefetch(&sets[pc[kk]]);
      }
      const std::size_t k = static_cast<std::size_t>(touching_[s + j]);
      view.gather(L, j, first[k], second[k]);
      L.hx[j] = hist[3 * k], L.hy[j] = hist[3 * k + 1], L.hz[j] = hist[3 * k + 2];
      L.set_coefficients(j, sets[pc[k]]);
    }
    evaluate_contacts(model_.law(), L, nb, dt);
    for (std::size_t j = 0; j < nb; ++j) {
      const std::size_t k = static_cast<std::size_t>(touching_[s + j]);
      hist[3 * k] = L.hx[j], hist[3 * k + 1] = L.hy[j], hist[3 * k + 2] = L.hz[j];
      view.accumulate(L, j, first[k], second[k]);
    }
  }
}

}  // namespace tessera
