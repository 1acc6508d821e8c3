// SPDX-License-Identifier: MIT
#include "solid/walls.hpp"

#include "core/errors.hpp"

namespace tessera {

void Walls::add_plane(const Vec3& point, const Vec3& normal, int material) {
  WallPrimitive w;
  w.kind = WallPrimitive::Kind::plane;
  w.point = point;
  w.normal = normal / norm(normal);
  w.material = material;
  prims_.push_back(w);
}

void Walls::add_box_inside(const Vec3& lo, const Vec3& hi, int material) {
  for (int d = 0; d < 3; ++d) {
    Vec3 n;
    n[d] = 1.0;
    add_plane(lo, n, material);
    add_plane(hi, -n, material);
  }
}

Walls::Walls(const ConfigNode& solid, const ContactModel& model) {
  for (const auto& w : solid.list("walls")) {
    const std::string type = w.choice("type", {"plane", "box"});
    const int mat = model.material_index(w.text("material"), w.key_path("material"));
    const std::size_t first = prims_.size();
    if (type == "plane") {
      const Vec3 point = w.vec3("point", Dim::length);
      const Vec3 normal = w.vec3("normal", Dim::none);
      if (norm(normal) == 0.0) w.fail("normal", "a non-zero vector");
      add_plane(point, normal, mat);
    } else {
      const Vec3 lo = w.vec3("min", Dim::length), hi = w.vec3("max", Dim::length);
      for (int d = 0; d < 3; ++d)
        if (!(hi[d] > lo[d])) w.fail("max", "larger than min in every direction");
      const std::string side = w.choice("side", {"inside", "outside"}, "inside");
      if (side == "inside") {
        add_box_inside(lo, hi, mat);
      } else {
        WallPrimitive p;
        p.kind = WallPrimitive::Kind::box_outside;
        p.lo = lo, p.hi = hi, p.material = mat;
        prims_.push_back(p);
      }
    }
    for (std::size_t k = first; k < prims_.size(); ++k) prims_[k].key = w.path();
  }
}

void Walls::check_pairs(const ContactModel& model, const std::vector<int>& body_materials) const {
  for (const auto& w : prims_)
    for (int m : body_materials)
      if (!model.has_pair(m, w.material))
        throw InputError("solid.contact.pairs", "",
                         "needs an entry for materials [" + model.materials()[m].name + ", " +
                             model.materials()[w.material].name + "] (used by " + w.key + ")");
}

}  // namespace tessera
