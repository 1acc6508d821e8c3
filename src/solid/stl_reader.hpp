// SPDX-License-Identifier: MIT
// STL surface meshes (ASCII and binary) for triangle-mesh walls. STL has no units: coordinates are
// multiplied by `scale` (metres per file unit). Identical vertices are merged, so triangles that
// share an edge share its nodes.
#pragma once
#include <string>

#include "solid/gmsh_reader.hpp"

namespace tessera {

// Returns nodes and triangles (no tetrahedra). Throws InputError naming the file for bad input.
TetMesh read_stl(const std::string& path, double scale = 1.0);

}  // namespace tessera
