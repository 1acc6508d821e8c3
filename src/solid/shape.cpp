// SPDX-License-Identifier: MIT
#include "solid/shape.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "core/errors.hpp"
#include "solid/gmsh_reader.hpp"
#include "solid/tet_mass_properties.hpp"

namespace tessera {

void ellipsoid_mesh(const Vec3& semi_axes, int rings, int segments, std::vector<Vec3>& nodes,
                    std::vector<std::array<int, 4>>& tets) {
  const double a = semi_axes.x, b = semi_axes.y, c = semi_axes.z;
  nodes = {{0, 0, 0}, {a, 0, 0}, {-a, 0, 0}};
  tets.clear();
  // Rings at equal polar angle; alternate rings turn by half a segment (better triangles).
  for (int i = 1; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = std::numbers::pi * i / (rings + 1);
      const double ph = 2 * std::numbers::pi * (j + 0.5 * (i % 2)) / segments;
      nodes.push_back({a * std::cos(th), b * std::sin(th) * std::cos(ph), c * std::sin(th) * std::sin(ph)});
    }
  auto ring = [&](int i, int j) { return 3 + (i - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) {
    tets.push_back({0, 1, ring(1, j), ring(1, j + 1)});
    tets.push_back({0, 2, ring(rings, j), ring(rings, j + 1)});
    for (int i = 1; i < rings; ++i) {
      // Quad (i, j) (i, j+1) (i+1, j+1) (i+1, j), split along the diagonal that the stagger favours.
      if (i % 2) {
        tets.push_back({0, ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
        tets.push_back({0, ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      } else {
        tets.push_back({0, ring(i, j), ring(i + 1, j), ring(i, j + 1)});
        tets.push_back({0, ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)});
      }
    }
  }
}

ShapeTemplate ShapeTemplate::from_mesh(std::string name, std::vector<Vec3> nodes, std::vector<std::array<int, 4>> tets,
                                       int sphere_count, double sphere_radius) {
  ShapeTemplate s;
  s.name = std::move(name);
  const MassProperties mp = tet_mass_properties(nodes, tets, 1.0);
  // Body frame: x_body = A^T (x - centroid), A = principal axes as columns.
  for (auto& p : nodes) {
    const Vec3 d = p - mp.centroid;
    p = {dot(d, mp.principal_axes[0]), dot(d, mp.principal_axes[1]), dot(d, mp.principal_axes[2])};
  }
  s.nodes = std::move(nodes);
  s.tetrahedra = std::move(tets);
  s.volume = mp.volume;
  s.inertia_per_density = mp.principal_moments;
  s.surface = boundary_triangles(s.nodes, s.tetrahedra);
  const ContactSpheres cs = place_contact_spheres(s.nodes, s.tetrahedra, sphere_count, sphere_radius);
  s.spheres = cs.centres;
  s.sphere_radius = cs.radius;
  for (const auto& c : s.spheres) s.bounding_radius = std::max(s.bounding_radius, norm(c) + cs.radius);
  s.envelope = envelope_deviation(s.nodes, s.surface, cs);
  s.convex = bounds_convex_polytope(s.nodes, s.surface, s.volume);
  return s;
}

bool bounds_convex_polytope(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 3>>& surface,
                            double volume) {
  if (surface.size() < 4 || nodes.empty()) return false;
  Vec3 lo = nodes[0], hi = nodes[0];
  for (const Vec3& p : nodes)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d]);
  const double tol = 1e-10 * norm(hi - lo);
  double enclosed = 0;  // divergence theorem over the triangles
  for (const auto& tri : surface) {
    const Vec3 &a = nodes[static_cast<std::size_t>(tri[0])], &b = nodes[static_cast<std::size_t>(tri[1])],
               &c = nodes[static_cast<std::size_t>(tri[2])];
    const Vec3 n = cross(b - a, c - a);
    const double area2 = norm(n);
    if (!(area2 > 0)) return false;
    for (const Vec3& p : nodes)
      if (dot(n, p - a) > tol * area2) return false;
    enclosed += dot(a, cross(b, c)) / 6;
  }
  return std::abs(enclosed - volume) <= 1e-9 * volume;
}

double farthest_node(const ShapeTemplate& t) {
  double r = 0;
  for (const Vec3& n : t.nodes) r = std::max(r, norm(n));
  return r;
}

std::vector<ShapeTemplate> read_shapes(const ConfigNode& solid, const std::string& case_dir) {
  std::vector<ShapeTemplate> out;
  for (const ConfigNode& n : solid.list("shapes")) {
    const std::string name = n.text("name");
    if (name == "sphere") n.fail("name", "a name other than 'sphere' (shape 0, the plain sphere)");
    for (const auto& s : out)
      if (s.name == name) n.fail("name", "a name not used by another shape");
    std::vector<Vec3> nodes;
    std::vector<std::array<int, 4>> tets;
    if (n.has("mesh") == n.has("spheroid")) n.fail("mesh", "exactly one of 'mesh' (a Gmsh file) or 'spheroid'");
    if (n.has("mesh")) {
      std::filesystem::path path = n.text("mesh");
      if (path.is_relative()) path = std::filesystem::path(case_dir) / path;
      const double scale = n.real("mesh_scale", Dim::none, Range::positive(), 1.0);
      TetMesh m = read_gmsh(path.string());
      if (m.tetrahedra.empty()) n.fail("mesh", "a Gmsh mesh with tetrahedra (3D mesh, gmsh -3)");
      for (auto& p : m.nodes) p = p * scale;
      // Keep only nodes used by tetrahedra (surface-only or stray points would skew placement).
      std::vector<int> index(m.nodes.size(), -1);
      for (auto& t : m.tetrahedra)
        for (int& v : t) {
          if (index[v] < 0) index[v] = static_cast<int>(nodes.size()), nodes.push_back(m.nodes[v]);
          v = index[v];
        }
      tets = std::move(m.tetrahedra);
    } else {
      const ConfigNode g = n.section("spheroid");
      const Vec3 axes = g.vec3("semi_axes", Dim::length);
      if (!(axes.x > 0 && axes.y > 0 && axes.z > 0)) g.fail("semi_axes", "three positive lengths");
      const int rings = static_cast<int>(g.integer("rings", 1, 200, 5));
      const int segments = static_cast<int>(g.integer("segments", 3, 400, 9));
      ellipsoid_mesh(axes, rings, segments, nodes, tets);
    }
    const ConfigNode cs = n.section("contact_spheres");
    const int count = static_cast<int>(cs.integer("count", 1, 100000));
    const double radius = cs.real("radius", Dim::length, Range::positive());
    out.push_back(ShapeTemplate::from_mesh(name, std::move(nodes), std::move(tets), count, radius));
    const auto& s = out.back();
    if (s.envelope.overshoot > 0.25 * radius)
      cs.fail("radius", "a radius below the surface's smallest radius of curvature: spheres of this radius reach " +
                            std::to_string(s.envelope.overshoot) + " m outside the surface");
  }
  return out;
}

}  // namespace tessera
