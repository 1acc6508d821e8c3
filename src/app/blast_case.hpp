// SPDX-License-Identifier: MIT
// The blast case's section read once (src/app/scene_blast.cpp): the mesh, the fracture settings,
// the borehole and the process grid's box. The scene and `tessera balance` both use it.
#pragma once
#include <mpi.h>

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

// A blast checkpoint (scene_blast.cpp writes it) restored into `solver` (built on the case's mesh):
// the elements' and bonds' state, the contact list, the dashpots' frozen orientations, the clock.
// Collective on comm. Throws InputError where the checkpoint is not of this mesh. Returns the probe's.
struct BlastCheckpoint {
  double probe_displacement = 0;
  bool probed = false;
};
BlastCheckpoint read_blast_checkpoint(const std::string& path, MPI_Comm comm, FractureSolver& solver);

}  // namespace tessera
