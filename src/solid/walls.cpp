// SPDX-License-Identifier: MIT
#include "solid/walls.hpp"

#include <filesystem>

#include "core/errors.hpp"
#include "solid/club_head.hpp"
#include "solid/gmsh_reader.hpp"
#include "solid/stl_reader.hpp"

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

namespace {

MeshWall read_mesh_wall(const ConfigNode& w, int material, const std::string& case_dir) {
  MeshWall m;
  m.key = w.path();
  m.material = material;
  TetMesh mesh;
  if (w.has("club") == w.has("file")) w.fail("file", "either a mesh file or a generated club: {...}, not both");
  if (const auto club = w.optional_section("club")) {
    // The bunker-shot seed's club head (club_head.hpp), its leading edge at `leading_edge`, the
    // side surface extruded over `width` along y.
    ClubHeadDesign d;
    d.face_length = club->real("face_length", Dim::length, Range::positive(), d.face_length);
    d.loft_deg = club->real("loft_deg", Dim::none, Range::half_open(0, 90), d.loft_deg);
    d.bounce_deg = club->real("bounce_deg", Dim::none, Range::half_open(0, 45), d.bounce_deg);
    d.sole_width = club->real("sole_width", Dim::length, Range::positive(), d.sole_width);
    d.sole_camber = club->real("sole_camber", Dim::length, Range::non_negative(), d.sole_camber);
    const Vec3 edge = club->vec3("leading_edge", Dim::length);
    const double width = club->real("width", Dim::length, Range::positive());
    std::vector<Vec3> nodes;
    extrude_outline(club_head_outline(d), edge.y, width, nodes, mesh.triangles);
    for (const auto& p : nodes) mesh.nodes.push_back({p.x + edge.x, p.y, p.z + edge.z});
  } else {
    std::filesystem::path path = w.text("file");
    if (path.is_relative()) path = std::filesystem::path(case_dir) / path;
    const double scale = w.real("scale", Dim::none, Range::positive(), 1.0);
    const std::string ext = path.extension().string();
    if (ext == ".stl" || ext == ".STL") {
      mesh = read_stl(path.string(), scale);
    } else if (ext == ".msh") {
      mesh = read_gmsh(path.string());
      for (auto& p : mesh.nodes) p = p * scale;
    } else {
      w.fail("file", "an STL (.stl) or Gmsh (.msh) surface mesh");
    }
  }
  if (mesh.triangles.empty()) w.fail("file", "a mesh with triangles");
  m.triangles = mesh.triangles;
  const ConfigNode motion = w.section("motion");
  const std::string type = motion.choice("type", {"fixed", "prescribed", "pivot"});
  Vec3 origin;
  if (type == "prescribed") {
    m.motion = MeshWall::Motion::prescribed;
    origin = motion.vec3("centre", Dim::length, Vec3{});
    m.velocity = motion.vec3("velocity", Dim::velocity, Vec3{});
    m.omega = motion.vec3("angular_velocity", Dim::angular_velocity, Vec3{});
  } else if (type == "pivot") {
    m.motion = MeshWall::Motion::pivot;
    origin = motion.vec3("pivot", Dim::length);
    m.axis = motion.vec3("axis", Dim::none);
    if (norm(m.axis) == 0.0) motion.fail("axis", "a non-zero vector");
    m.axis = m.axis / norm(m.axis);
    m.inertia = motion.real("moment_of_inertia", Dim::moment_of_inertia, Range::positive());
    m.applied_moment = motion.real("applied_moment", Dim::moment, Range{-1e300, 1e300, false, false}, 0.0);
    m.theta_dot = motion.real("angular_velocity", Dim::angular_velocity, Range{-1e300, 1e300, false, false}, 0.0);
    m.mass = motion.real("mass", Dim::mass, Range::non_negative(), 0.0);
    m.centre_of_mass = motion.vec3("centre_of_mass", Dim::length, origin) - origin;
  }
  m.origin = origin;
  for (const auto& p : mesh.nodes) m.local.push_back(p - origin);
  return m;
}

}  // namespace

Walls::Walls(const ConfigNode& solid, const ContactModel& model, const std::string& case_dir) {
  for (const auto& w : solid.list("walls")) {
    const std::string type = w.choice("type", {"plane", "box", "mesh"});
    const int mat = model.material_index(w.text("material"), w.key_path("material"));
    const std::size_t first = prims_.size();
    if (type == "mesh") {
      add_mesh(read_mesh_wall(w, mat, case_dir));
      continue;
    }
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

void Walls::add_mesh(MeshWall m) {
  if (m.motion == MeshWall::Motion::pivot) {
    m.q0 = m.q;  // origin: the pivot
    m.omega = m.axis * m.theta_dot;
  }
  m.place();
  meshes_.push_back(std::move(m));
}

void Walls::check_pairs(const ContactModel& model, const std::vector<int>& body_materials) const {
  for (const auto& m : meshes_)
    for (int b : body_materials)
      if (!model.has_pair(b, m.material))
        throw InputError("solid.contact.pairs", "",
                         "an entry for materials [" + model.materials()[b].name + ", " +
                             model.materials()[m.material].name + "] (mesh wall " + m.key + ")");
  for (const auto& w : prims_)
    for (int m : body_materials)
      if (!model.has_pair(m, w.material))
        throw InputError("solid.contact.pairs", "",
                         "needs an entry for materials [" + model.materials()[m].name + ", " +
                             model.materials()[w.material].name + "] (used by " + w.key + ")");
}

}  // namespace tessera
