// SPDX-License-Identifier: MIT
// A block meshed into tetrahedra, each a rigid element (docs/theory.md B1): its mass and principal
// inertia (T10), its vertices in its body frame (origin at the centroid, principal axes), and the
// faces: every face two elements share is a bond (master = the lower element index, as in the seed),
// every other face is on the block's surface. Built identically on every rank from the mesh, with
// the elements in the Morton (Z-order) of their centroids: an element's bonds and neighbours are
// close in memory whatever order the mesher wrote (mesh_index maps back to the file's order).
#pragma once
#include <array>
#include <vector>

#include "core/vec3.hpp"
#include "solid/gmsh_reader.hpp"
#include "solid/rigid_rotation.hpp"

namespace tessera {

// Local face f of a tetrahedron is the one opposite its vertex f.
constexpr int kFaceVertices[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct BondGeometry {
  int master = 0, slave = 0;    // element indices, master < slave
  int master_face = 0, slave_face = 0;
  std::array<int, 3> nodes{};   // mesh nodes of the face
  std::array<Vec3, 3> at_master{}, at_slave{};  // the three vertices in each element's body frame
  Vec3 normal{}, xi{}, eta{};   // the master face's frame in the master's body frame (outward normal)
  double area = 0;
};

struct SurfaceFace {
  int element = 0, face = 0;
  std::array<int, 3> nodes{};
  Vec3 centroid_body{}, normal_body{};  // outward, in the element's body frame
  double area = 0;
};

struct BondedBlock {
  std::vector<Vec3> nodes;                      // the mesh's nodes (initial positions)
  std::vector<std::array<int, 4>> tets;         // mesh node indices per element
  std::vector<int> mesh_index;                  // each element's index among the mesh file's tetrahedra
  std::vector<double> mass, volume;
  std::vector<Vec3> inertia;                    // principal moments
  std::vector<Vec3> x0;                         // initial centroids
  std::vector<Quaternion> q0;                   // initial orientations (body -> world)
  std::vector<std::array<Vec3, 4>> vertices;    // body frame
  std::vector<BondGeometry> bonds;              // sorted by (master, slave)
  std::vector<SurfaceFace> surface;             // sorted by (element, face)
  double min_edge = 0, max_edge = 0;

  std::size_t size() const { return mass.size(); }
};

// Throws InputError for a degenerate element or a face shared by more than two elements.
BondedBlock build_bonded_block(const TetMesh& mesh, double density);

// Outward unit normal and area of local face f of element e, in its body frame.
void face_frame(const BondedBlock& b, int e, int f, Vec3& normal, Vec3& centroid, double& area);

}  // namespace tessera
