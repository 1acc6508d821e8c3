// SPDX-License-Identifier: MIT
// The blast case's section read once (src/app/scene_blast.cpp): the mesh, the fracture settings,
// the borehole and the process grid's box. The scene and `tessera balance` both use it.
#pragma once
#include <array>
#include <optional>
#include <string>

#include "core/config.hpp"
#include "fracture/fracture_solver.hpp"
#include "solid/gmsh_reader.hpp"

namespace tessera {

struct BlastCase {
  std::string mesh_file;
  TetMesh mesh;
  FractureSettings settings;
  std::optional<Borehole> hole;
  std::array<int, 3> grid{0, 0, 0};  // blast.process_grid (0: chosen)
  Vec3 lo, hi;                       // the mesh's box, a little enlarged: the process grid's box
};

// Throws InputError for a bad key or mesh (paths relative to case_dir).
BlastCase read_blast_case(const ConfigNode& root, const std::string& case_dir);

}  // namespace tessera
