// SPDX-License-Identifier: MIT
// Triangle-mesh walls (T14): a surface mesh (STL, or the triangles of a Gmsh mesh) that bodies'
// contact spheres touch face, edge or vertex, counted once where triangles meet (T11). A mesh moves
// as a rigid surface in one of three ways:
//   fixed       it stays where it is;
//   prescribed  it translates with `velocity` and turns with `angular_velocity` about `centre`;
//   pivot       it turns about a fixed `axis` through `pivot` by theta'' = (Mo + Mg + Mp) / Ih
//               (the bunker seed's eq. 8): Mo the applied moment, Mg gravity's moment on its mass
//               at its centre of mass, Mp the contact forces' moment, Ih its moment of inertia
//               about the axis; integrated by velocity Verlet with the bodies.
// Contacts use the wall law (T7) with the mesh's material; the wall's velocity at the contact point
// enters the relative velocity. The force and moment the bodies exert on each mesh are reported.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "core/vec3.hpp"
#include "solid/rigid_rotation.hpp"

namespace tessera {

struct MeshWall {
  enum class Motion { fixed, prescribed, pivot };
  std::string key;  // case-file key, for messages
  int material = 0;
  Motion motion = Motion::fixed;
  std::vector<Vec3> local;  // nodes relative to `origin` at orientation `q0` (the file's frame, shifted)
  std::vector<std::array<int, 3>> triangles;
  // State: nodes = origin + R(q) local.
  Vec3 origin;
  Quaternion q;
  Vec3 velocity, omega;  // prescribed: given; pivot: omega = theta_dot * axis
  // Pivot.
  Vec3 axis{0, 0, 1};
  double theta = 0, theta_dot = 0, theta_ddot = 0;
  double inertia = 0, applied_moment = 0, mass = 0;
  Vec3 centre_of_mass;  // relative to the pivot at theta = 0
  Quaternion q0;        // orientation at theta = 0
  // Current world nodes and the load on the mesh at the last force evaluation (all ranks).
  std::vector<Vec3> nodes;
  Vec3 force, moment;         // moment about `origin`
  double contact_moment = 0;  // pivot: axis component of `moment`

  void place();  // nodes from origin, q
  Vec3 velocity_at(const Vec3& p) const { return velocity + cross(omega, p - origin); }
  // Advances the motion over dt (pivot: the drift of velocity Verlet after the first half-kick).
  void advance(double dt);
  // Pivot: theta'' from the applied, gravity and contact moments.
  void update_acceleration(const Vec3& gravity);
};

}  // namespace tessera
