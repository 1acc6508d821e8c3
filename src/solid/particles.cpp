// SPDX-License-Identifier: MIT
#include "solid/particles.hpp"

#include <utility>

namespace tessera {

void ParticleStore::resize(std::size_t n) {
  id.resize(n);
  order.resize(n);
  material.resize(n);
  shape.resize(n);
  radius.resize(n);
  mass.resize(n);
  inertia.resize(n);
  x.resize(3 * n);
  v.resize(3 * n);
  omega.resize(3 * n);
  q.resize(4 * n);
  f.resize(3 * n);
  torque.resize(3 * n);
  wall_history.resize(3 * static_cast<std::size_t>(wall_slots) * n);
  f_ext.resize(3 * n);
  t_ext.resize(3 * n);
}

std::size_t ParticleStore::push_back(std::int64_t gid, int mat, double r, double m, double inertia_moment,
                                     const Vec3& pos, const Vec3& vel, const Vec3& w) {
  const std::size_t i = id.size();
  resize(i + 1);
  id[i] = gid;
  order[i] = -1;  // assigned at set-up (DemSolver::assign_order)
  material[i] = mat;
  shape[i] = 0;
  radius[i] = r;
  mass[i] = m;
  inertia[i] = inertia_moment;
  pos.store(&x[3 * i]);
  vel.store(&v[3 * i]);
  w.store(&omega[3 * i]);
  q[4 * i] = 1.0;
  q[4 * i + 1] = q[4 * i + 2] = q[4 * i + 3] = 0.0;
  for (int k = 0; k < 3; ++k) f[3 * i + k] = torque[3 * i + k] = f_ext[3 * i + k] = t_ext[3 * i + k] = 0.0;
  for (int k = 0; k < 3 * wall_slots; ++k) wall_history[3 * wall_slots * i + k] = 0.0;
  return i;
}

void ParticleStore::copy(std::size_t s, std::size_t d) {
  if (s == d) return;
  id[d] = id[s];
  order[d] = order[s];
  material[d] = material[s];
  shape[d] = shape[s];
  radius[d] = radius[s];
  mass[d] = mass[s];
  inertia[d] = inertia[s];
  for (int k = 0; k < 3; ++k) {
    x[3 * d + k] = x[3 * s + k];
    v[3 * d + k] = v[3 * s + k];
    omega[3 * d + k] = omega[3 * s + k];
    f[3 * d + k] = f[3 * s + k];
    torque[3 * d + k] = torque[3 * s + k];
    f_ext[3 * d + k] = f_ext[3 * s + k];
    t_ext[3 * d + k] = t_ext[3 * s + k];
  }
  for (int k = 0; k < 4; ++k) q[4 * d + k] = q[4 * s + k];
  const std::size_t w = 3 * static_cast<std::size_t>(wall_slots);
  for (std::size_t k = 0; k < w; ++k) wall_history[w * d + k] = wall_history[w * s + k];
}

void ParticleStore::swap(std::size_t a, std::size_t b) {
  if (a == b) return;
  std::swap(id[a], id[b]);
  std::swap(order[a], order[b]);
  std::swap(material[a], material[b]);
  std::swap(shape[a], shape[b]);
  std::swap(radius[a], radius[b]);
  std::swap(mass[a], mass[b]);
  std::swap(inertia[a], inertia[b]);
  for (int k = 0; k < 3; ++k) {
    std::swap(x[3 * a + k], x[3 * b + k]);
    std::swap(v[3 * a + k], v[3 * b + k]);
    std::swap(omega[3 * a + k], omega[3 * b + k]);
    std::swap(f[3 * a + k], f[3 * b + k]);
    std::swap(torque[3 * a + k], torque[3 * b + k]);
    std::swap(f_ext[3 * a + k], f_ext[3 * b + k]);
    std::swap(t_ext[3 * a + k], t_ext[3 * b + k]);
  }
  for (int k = 0; k < 4; ++k) std::swap(q[4 * a + k], q[4 * b + k]);
  const std::size_t w = 3 * static_cast<std::size_t>(wall_slots);
  for (std::size_t k = 0; k < w; ++k) std::swap(wall_history[w * a + k], wall_history[w * b + k]);
}

void ParticleStore::pack(std::size_t i, std::vector<double>& buf) const {
  buf.push_back(static_cast<double>(id[i]));
  buf.push_back(material[i]);
  buf.push_back(shape[i]);
  buf.push_back(radius[i]);
  buf.push_back(mass[i]);
  buf.push_back(inertia[i]);
  for (int k = 0; k < 3; ++k) buf.push_back(x[3 * i + k]);
  for (int k = 0; k < 3; ++k) buf.push_back(v[3 * i + k]);
  for (int k = 0; k < 3; ++k) buf.push_back(omega[3 * i + k]);
  for (int k = 0; k < 4; ++k) buf.push_back(q[4 * i + k]);
  for (int k = 0; k < 3; ++k) buf.push_back(f[3 * i + k]);
  for (int k = 0; k < 3; ++k) buf.push_back(torque[3 * i + k]);
  buf.push_back(static_cast<double>(order[i]));
  const std::size_t w = 3 * static_cast<std::size_t>(wall_slots);
  for (std::size_t k = 0; k < w; ++k) buf.push_back(wall_history[w * i + k]);
  for (int k = 0; k < 3; ++k) buf.push_back(f_ext[3 * i + k]);
  for (int k = 0; k < 3; ++k) buf.push_back(t_ext[3 * i + k]);
}

std::size_t ParticleStore::unpack_append(const double* b, bool with_loads) {
  const std::size_t i = id.size();
  resize(i + 1);
  id[i] = static_cast<std::int64_t>(b[0]);
  material[i] = static_cast<std::int32_t>(b[1]);
  shape[i] = static_cast<std::int32_t>(b[2]);
  radius[i] = b[3];
  mass[i] = b[4];
  inertia[i] = b[5];
  for (int k = 0; k < 3; ++k) x[3 * i + k] = b[6 + k];
  for (int k = 0; k < 3; ++k) v[3 * i + k] = b[9 + k];
  for (int k = 0; k < 3; ++k) omega[3 * i + k] = b[12 + k];
  for (int k = 0; k < 4; ++k) q[4 * i + k] = b[15 + k];
  for (int k = 0; k < 3; ++k) f[3 * i + k] = b[19 + k];
  for (int k = 0; k < 3; ++k) torque[3 * i + k] = b[22 + k];
  order[i] = static_cast<std::int64_t>(b[25]);
  const std::size_t w = 3 * static_cast<std::size_t>(wall_slots);
  for (std::size_t k = 0; k < w; ++k) wall_history[w * i + k] = b[26 + k];
  for (int k = 0; k < 3; ++k) {
    f_ext[3 * i + k] = with_loads ? b[26 + w + k] : 0.0;
    t_ext[3 * i + k] = with_loads ? b[29 + w + k] : 0.0;
  }
  return i;
}

void ParticleStore::pack_ghost(std::size_t i, std::vector<double>& buf) const {
  buf.push_back(static_cast<double>(id[i]));
  buf.push_back(static_cast<double>(order[i]));
  buf.push_back(material[i]);
  buf.push_back(shape[i]);
  buf.push_back(radius[i]);
  buf.push_back(mass[i]);
  for (int k = 0; k < 3; ++k) buf.push_back(x[3 * i + k]);
  for (int k = 0; k < 3; ++k) buf.push_back(v[3 * i + k]);
  for (int k = 0; k < 3; ++k) buf.push_back(omega[3 * i + k]);
  for (int k = 0; k < 4; ++k) buf.push_back(q[4 * i + k]);
}

void ParticleStore::unpack_ghost_append(const double* b) {
  const std::size_t i = id.size();
  resize(i + 1);
  id[i] = static_cast<std::int64_t>(b[0]);
  order[i] = static_cast<std::int64_t>(b[1]);
  material[i] = static_cast<std::int32_t>(b[2]);
  shape[i] = static_cast<std::int32_t>(b[3]);
  radius[i] = b[4];
  mass[i] = b[5];
  inertia[i] = 0.4 * b[5] * b[4] * b[4];  // spheres; shaped bodies take theirs from the template
  for (int k = 0; k < 3; ++k) x[3 * i + k] = b[6 + k];
  for (int k = 0; k < 3; ++k) v[3 * i + k] = b[9 + k];
  for (int k = 0; k < 3; ++k) omega[3 * i + k] = b[12 + k];
  for (int k = 0; k < 4; ++k) q[4 * i + k] = b[15 + k];
}

}  // namespace tessera
