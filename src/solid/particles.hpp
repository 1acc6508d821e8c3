// SPDX-License-Identifier: MIT
// Rigid bodies in structure-of-arrays storage. Indices [0, owned) are the bodies this rank
// integrates; [owned, owned + ghosts) are read-only copies of neighbours' bodies within the halo.
//
// A body here is a sphere (shape 0): its single contact sphere sits at the centre of mass. The
// shape id selects a shape template (tetrahedra + contact spheres) in the next step of the project;
// kernels already address bodies through these arrays only, so templates add arrays, not rewrites.
//
// Vector quantities are contiguous arrays of 3 (or 4) doubles per body: x[3*i + k].
#pragma once
#include <cstdint>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

struct ParticleStore {
  // Per body.
  std::vector<std::int64_t> id;  // global id, unique, stable for the whole run (user-facing)
  // Canonical order key, unique, permanent: the body's rank in a Morton (Z-order) sort of the initial
  // positions. Storage, contact orientation (lower key first) and the order forces are summed in
  // follow it: neighbours are close in memory, and the order is the same on every decomposition.
  std::vector<std::int64_t> order;
  std::vector<std::int32_t> material;
  std::vector<std::int32_t> shape;  // 0 = sphere
  std::vector<double> radius;       // contact radius (sphere)
  std::vector<double> mass;
  std::vector<double> inertia;       // principal moment (sphere: 2/5 m r^2)
  std::vector<double> x, v, omega;   // 3 per body
  std::vector<double> q;             // orientation quaternion (w, x, y, z), 4 per body
  std::vector<double> f, torque;     // 3 per body, owned bodies only are meaningful
  std::vector<double> wall_history;  // 3 per body per wall slot: tangential spring (eq. 5)
  // External load (the fluid's force on the body, a borehole's pressure): 3 per body, added to the
  // contact force and torque in both half-kicks while DemSolver::external_loads() is on. Set by
  // the body's owner; travels with the body (migration, ordering, checkpoints).
  std::vector<double> f_ext, t_ext;

  int wall_slots = 0;
  std::size_t owned = 0, ghosts = 0;

  std::size_t size() const { return id.size(); }  // owned + ghosts once set up
  void resize(std::size_t n);
  // Appends one body (owned or ghost block must be managed by the caller).
  std::size_t push_back(std::int64_t gid, int mat, double r, double m, double inertia_moment, const Vec3& pos,
                        const Vec3& vel, const Vec3& w);
  // Copies every per-body field of body src into slot dst.
  void copy(std::size_t src, std::size_t dst);
  void swap(std::size_t a, std::size_t b);

  Vec3 pos(std::size_t i) const { return Vec3::load(&x[3 * i]); }
  Vec3 vel(std::size_t i) const { return Vec3::load(&v[3 * i]); }
  Vec3 ang(std::size_t i) const { return Vec3::load(&omega[3 * i]); }

  // Full state of one body, for migration and checkpoints: number of doubles per body.
  // Layout: the 26 fields of packed_size_without_loads, the wall histories, then f_ext and t_ext.
  int packed_size() const { return 32 + 3 * wall_slots; }
  int packed_size_without_loads() const { return 26 + 3 * wall_slots; }  // checkpoints before 2026-11-29
  void pack(std::size_t i, std::vector<double>& buf) const;
  // Appends a body unpacked from buf; returns its index. with_loads = false reads the layout
  // without external loads (older checkpoints) and sets them to zero.
  std::size_t unpack_append(const double* buf, bool with_loads = true);

  // What a ghost needs for contact forces: id, order, material, shape, radius, mass, x, v, omega, q.
  static constexpr int ghost_size = 19;
  void pack_ghost(std::size_t i, std::vector<double>& buf) const;
  void unpack_ghost_append(const double* buf);
  static constexpr int forward_size = 9;  // x, v, omega, sent every step (+ q for shaped bodies)
};

}  // namespace tessera
