// SPDX-License-Identifier: MIT
// Shape templates (T13): what many bodies of one kind share. A template is a tetrahedral mesh moved
// to its body frame (origin at the centroid, axes along the principal axes of inertia), its mass
// properties per unit density (from the tetrahedra, T10), and its contact spheres (T12) in that
// frame. A body made from a template has mass = density * volume and principal moments
// density * inertia_per_density; its orientation q maps the body frame to the world.
//
// Shape 0 is always the plain sphere (one contact sphere at the centre, radius per body): spheres
// keep their own fast path. Templates are read from `solid.shapes` (a list):
//
//   shapes:
//     - name: grain
//       spheroid: {semi_axes: [0.635 mm, 0.26 mm, 0.26 mm], rings: 5, segments: 9}
//       # or: mesh: grain.msh   (Gmsh MSH 2.2/4.1 tetrahedra; mesh_scale: 1e-3 for a mesh in mm)
//       contact_spheres: {count: 75, radius: 0.1 mm}
#pragma once
#include <array>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/vec3.hpp"
#include "solid/contact_spheres.hpp"

namespace tessera {

struct ShapeTemplate {
  std::string name;
  std::vector<Vec3> nodes;  // body frame
  std::vector<std::array<int, 4>> tetrahedra;
  std::vector<std::array<int, 3>> surface;  // boundary triangles, outward
  double volume = 0;
  Vec3 inertia_per_density;   // principal moments / density (ascending)
  std::vector<Vec3> spheres;  // contact-sphere centres, body frame
  double sphere_radius = 0;
  double bounding_radius = 0;  // max |c| + sphere radius: the body's reach from its centre
  EnvelopeDeviation envelope;  // of the contact spheres against the mesh surface
  // The surface bounds a convex polytope (every node on the inner side of every surface triangle's
  // plane, and the surface encloses the tetrahedra's volume): the solid fraction lays the body out
  // as that one polytope (coupling/solid_phase.cpp, theory C1).
  bool convex = false;

  // Builds the template from a mesh in any frame: moves it to the principal frame, places spheres.
  static ShapeTemplate from_mesh(std::string name, std::vector<Vec3> nodes, std::vector<std::array<int, 4>> tets,
                                 int sphere_count, double sphere_radius);
};

// Closed tetrahedral mesh of an ellipsoid with semi-axes (a, b, c), the long axis along x: a fan of
// tetrahedra from the centre to a surface of `rings` latitude rings of `segments` nodes between the
// two poles (nodes: 3 + rings * segments; tetrahedra: 2 segments rings). Surface nodes lie on the
// ellipsoid, so the mesh is inscribed (its volume is below the ellipsoid's; T13).
void ellipsoid_mesh(const Vec3& semi_axes, int rings, int segments, std::vector<Vec3>& nodes,
                    std::vector<std::array<int, 4>>& tets);

// Whether the closed surface (outward triangles) bounds a convex polytope of the given volume: every
// node lies on the inner side of every triangle's plane (within 1e-10 of the mesh's size).
bool bounds_convex_polytope(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 3>>& surface,
                            double volume);

// The farthest node of the mesh from the body's centre: the reach of its tetrahedra (the solid
// fraction's lay-out, coupling/solid_phase.cpp; the scaling model's count of it, solid/rank_load).
double farthest_node(const ShapeTemplate& t);

// Reads `solid.shapes` (case_dir resolves relative mesh paths). Index k of the result is shape k+1.
std::vector<ShapeTemplate> read_shapes(const ConfigNode& solid, const std::string& case_dir);

}  // namespace tessera
