// SPDX-License-Identifier: MIT
#include "solid/contact_entities.hpp"

#include <array>

namespace tessera {

void ContactEntities::layout(const std::vector<ShapeTemplate>& shapes, std::int64_t key_stride) {
  const std::size_t n = p_.size();
  e_first_.resize(n + 1);
  e_reach_.resize(n);
  e_body_.clear(), e_key_.clear(), e_r_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    e_first_[i] = e_body_.size();
    if (i == p_.owned) e_owned_ = e_body_.size();
    const int sh = p_.shape[i];
    const std::size_t count = sh > 0 ? shapes[sh - 1].spheres.size() : 1;
    const double r = sh > 0 ? shapes[sh - 1].sphere_radius : p_.radius[i];
    e_reach_[i] = sh > 0 ? shapes[sh - 1].bounding_radius : r;
    for (std::size_t k = 0; k < count; ++k) {
      e_body_.push_back(static_cast<std::int32_t>(i));
      e_key_.push_back(p_.order[i] * key_stride + static_cast<std::int64_t>(k));
      e_r_.push_back(r);
    }
  }
  e_first_[n] = e_body_.size();
  if (n == p_.owned) e_owned_ = e_body_.size();
  geometry_.resize(e_body_.size());
  motion_.resize(e_body_.size());
  place(shapes, 0, n);
}

namespace {

// R(q) of a unit quaternion, row by row.
struct Rotation {
  double r00, r01, r02, r10, r11, r12, r20, r21, r22;
  explicit Rotation(const double* q) {
    const double qw = q[0], qx = q[1], qy = q[2], qz = q[3];
    r00 = 1 - 2 * (qy * qy + qz * qz), r01 = 2 * (qx * qy - qw * qz), r02 = 2 * (qx * qz + qw * qy);
    r10 = 2 * (qx * qy + qw * qz), r11 = 1 - 2 * (qx * qx + qz * qz), r12 = 2 * (qy * qz - qw * qx);
    r20 = 2 * (qx * qz - qw * qy), r21 = 2 * (qy * qz + qw * qx), r22 = 1 - 2 * (qx * qx + qy * qy);
  }
  // x + R c: every placement of an element (place, place_listed, position) is this expression.
  KernelGeometry at(const double* x, const Vec3& c, double r) const {
    const double ax = r00 * c.x + r01 * c.y + r02 * c.z;
    const double ay = r10 * c.x + r11 * c.y + r12 * c.z;
    const double az = r20 * c.x + r21 * c.y + r22 * c.z;
    return {x[0] + ax, x[1] + ay, x[2] + az, r};
  }
};

}  // namespace

void ContactEntities::place(const std::vector<ShapeTemplate>& shapes, std::size_t first_body, std::size_t end_body) {
  // Element e of body i: arm = R(q) c_e, x_e = x + arm, written to the kernel mirror (the elements'
  // only per-step storage). Velocities are made only for elements in contact (refresh_motion).
  KernelGeometry* __restrict g = geometry_.data();
  for (std::size_t i = first_body; i < end_body; ++i) {
    const int sh = p_.shape[i];
    const double* x = &p_.x[3 * i];
    const std::size_t e0 = e_first_[i], e1 = e_first_[i + 1];
    if (sh == 0) {
      g[e0] = {x[0], x[1], x[2], e_r_[e0]};
      continue;
    }
    const Rotation rot(&p_.q[4 * i]);
    const Vec3* c = shapes[sh - 1].spheres.data();
    const double r = shapes[sh - 1].sphere_radius;
    for (std::size_t e = e0; e < e1; ++e, ++c) g[e] = rot.at(x, *c, r);
  }
}

void ContactEntities::place_listed(const std::vector<ShapeTemplate>& shapes, const std::int32_t* first,
                                   const std::int32_t* last) {
  KernelGeometry* __restrict g = geometry_.data();
  std::size_t body = static_cast<std::size_t>(-1);
  Rotation rot(std::array<double, 4>{1, 0, 0, 0}.data());
  for (; first != last; ++first) {
    const auto e = static_cast<std::size_t>(*first);
    const auto i = static_cast<std::size_t>(e_body_[e]);
    const int sh = p_.shape[i];
    const double* x = &p_.x[3 * i];
    if (sh == 0) {
      g[e] = {x[0], x[1], x[2], e_r_[e]};
      continue;
    }
    if (i != body) rot = Rotation(&p_.q[4 * i]), body = i;
    g[e] = rot.at(x, shapes[sh - 1].spheres[e - e_first_[i]], shapes[sh - 1].sphere_radius);
  }
}

Vec3 ContactEntities::position(const std::vector<ShapeTemplate>& shapes, std::size_t e) const {
  if (!shaped_) return p_.pos(e);
  const auto i = static_cast<std::size_t>(e_body_[e]);
  const int sh = p_.shape[i];
  if (sh == 0) return p_.pos(i);
  const KernelGeometry g = Rotation(&p_.q[4 * i]).at(&p_.x[3 * i], shapes[sh - 1].spheres[e - e_first_[i]], 0.0);
  return {g.x, g.y, g.z};
}

void ContactEntities::refresh_motion(std::size_t e) {
  // v_e = v + w x (x_e - x), w: the velocity of contact sphere e from its body's.
  const std::size_t i = static_cast<std::size_t>(e_body_[e]);
  const KernelGeometry& g = geometry_[e];
  const double ax = g.x - p_.x[3 * i], ay = g.y - p_.x[3 * i + 1], az = g.z - p_.x[3 * i + 2];
  const double wx = p_.omega[3 * i], wy = p_.omega[3 * i + 1], wz = p_.omega[3 * i + 2];
  motion_[e] = {p_.v[3 * i] + (wy * az - wz * ay),
                p_.v[3 * i + 1] + (wz * ax - wx * az),
                p_.v[3 * i + 2] + (wx * ay - wy * ax),
                wx,
                wy,
                wz};
}

void ContactEntities::start_forces() {
  const std::size_t n = size();
  if (!discs()) {
    geometry_.resize(n);
    motion_.resize(n);
    // Forces go straight to bodies (shaped mode: element forces with their lever arms, in pair
    // order, which is canonical as for spheres), so the buffer is one slot per body.
    force_.assign(p_.size(), KernelForce{0, 0, 0, 0, 0, 0});
    return;
  }
  disc_.resize(n);
  disc_force_.assign(n, DiscForce{0, 0, 0});
}

}  // namespace tessera
