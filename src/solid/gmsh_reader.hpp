// SPDX-License-Identifier: MIT
// Gmsh meshes (MSH 4.1 and 2.2, ASCII): nodes, 4-node tetrahedra and 3-node triangles, for body
// shapes made of tetrahedra and for triangle-mesh walls. Other element types (points, lines) are
// skipped. Node tags are mapped to 0-based indices in file order.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

struct TetMesh {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tetrahedra;
  std::vector<std::array<int, 3>> triangles;
};

// Throws InputError naming the file (and line) for anything it cannot read.
TetMesh read_gmsh(const std::string& path);

}  // namespace tessera
