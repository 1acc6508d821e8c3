// SPDX-License-Identifier: MIT
#include "solid/mesh_walls.hpp"

#include <cmath>

namespace tessera {

void MeshWall::place() {
  nodes.resize(local.size());
  for (std::size_t k = 0; k < local.size(); ++k) nodes[k] = origin + q.rotate(local[k]);
}

void MeshWall::advance(double dt) {
  if (motion == Motion::fixed) return;
  if (motion == Motion::prescribed) {
    origin += velocity * dt;
  } else {
    theta += dt * theta_dot;
    omega = axis * theta_dot;
  }
  // Turn by |w| dt about w (exact for a constant w).
  const double w = norm(omega);
  if (motion == Motion::pivot) {
    q = Quaternion{std::cos(0.5 * theta), axis.x * std::sin(0.5 * theta), axis.y * std::sin(0.5 * theta),
                   axis.z * std::sin(0.5 * theta)} *
        q0;
  } else if (w > 0) {
    const Vec3 u = omega / w;
    const double s = std::sin(0.5 * w * dt);
    q = Quaternion{std::cos(0.5 * w * dt), u.x * s, u.y * s, u.z * s} * q;
  }
  place();
}

void MeshWall::update_acceleration(const Vec3& gravity) {
  if (motion != Motion::pivot) return;
  const Quaternion turn{std::cos(0.5 * theta), axis.x * std::sin(0.5 * theta), axis.y * std::sin(0.5 * theta),
                        axis.z * std::sin(0.5 * theta)};
  const double gravity_moment = dot(axis, cross(turn.rotate(centre_of_mass), gravity * mass));
  contact_moment = dot(axis, moment);
  theta_ddot = (applied_moment + gravity_moment + contact_moment) / inertia;
}

}  // namespace tessera
