// SPDX-License-Identifier: MIT
// The scene registry: one line per scene (name -> factory).
#pragma once
#include <memory>
#include <string>

#include "app/dem_scene.hpp"

namespace tessera {

std::unique_ptr<DemScene> make_deposition_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir);
std::unique_ptr<DemScene> make_bed_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir);
std::unique_ptr<DemScene> make_bunker_shot_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir);
// The flow solver alone (issue 4), or with bodies (`coupled`, issue 15): throws InputError in a build
// without PETSc.
std::unique_ptr<Scene> make_flow_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir, bool coupled);
// Bonded tetrahedra fractured by a borehole's gas pressure (scene_blast.cpp).
std::unique_ptr<Scene> make_blast_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir);

}  // namespace tessera
