// SPDX-License-Identifier: MIT
// Static walls: infinite planes and axis-aligned boxes (a container, `side: inside`, is its six
// faces as planes; an obstacle, `side: outside`, pushes spheres out of the box along the shortest
// way). Each primitive has one tangential-history slot per body, so the spring of eq. (5) travels
// with the body when it migrates. Wall contacts use the same contact law as body-body contacts,
// with the wall's material, m* = m and R* = R (T7).
#pragma once
#include <algorithm>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/vec3.hpp"
#include "solid/contact_model.hpp"
#include "solid/mesh_walls.hpp"

namespace tessera {

struct WallPrimitive {
  enum class Kind { plane, box_outside } kind = Kind::plane;
  Vec3 point, normal;  // plane: point on it, unit normal into the side bodies live on
  Vec3 lo, hi;         // box_outside
  int material = 0;
  std::string key;  // case-file key, for messages

  // Overlap (> 0 when touching) and unit normal from the wall to the sphere centre c.
  double overlap(const Vec3& c, double r, Vec3& n) const {
    if (kind == Kind::plane) {
      n = normal;
      return r - dot(c - point, normal);
    }
    Vec3 nearest{std::clamp(c.x, lo.x, hi.x), std::clamp(c.y, lo.y, hi.y), std::clamp(c.z, lo.z, hi.z)};
    Vec3 d = c - nearest;
    const double dist = norm(d);
    if (dist > 0.0) {
      n = d / dist;
      return r - dist;
    }
    // Centre inside the obstacle: leave through the nearest face.
    double best = c.x - lo.x;
    n = {-1, 0, 0};
    const double cand[5] = {hi.x - c.x, c.y - lo.y, hi.y - c.y, c.z - lo.z, hi.z - c.z};
    const Vec3 dirs[5] = {{1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
    for (int k = 0; k < 5; ++k)
      if (cand[k] < best) best = cand[k], n = dirs[k];
    return r + best;
  }
};

class Walls {
 public:
  Walls() = default;
  // Reads solid.walls: a list of {type: plane|box|mesh, ...}; case_dir resolves mesh files.
  Walls(const ConfigNode& solid, const ContactModel& model, const std::string& case_dir = ".");
  void add_plane(const Vec3& point, const Vec3& normal, int material);
  void add_box_inside(const Vec3& lo, const Vec3& hi, int material);

  const std::vector<WallPrimitive>& primitives() const { return prims_; }
  // Triangle-mesh walls (T14); their motion state lives here.
  void add_mesh(MeshWall m);
  const std::vector<MeshWall>& meshes() const { return meshes_; }
  std::vector<MeshWall>& meshes() { return meshes_; }
  int slots() const { return static_cast<int>(prims_.size()); }
  // Every body material must have contact parameters with every wall material.
  void check_pairs(const ContactModel& model, const std::vector<int>& body_materials) const;

 private:
  std::vector<WallPrimitive> prims_;
  std::vector<MeshWall> meshes_;
};

}  // namespace tessera
