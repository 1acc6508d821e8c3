// SPDX-License-Identifier: MIT
#include "app/scenes.hpp"

#include "core/errors.hpp"

namespace tessera {

std::unique_ptr<DemScene> make_dem_scene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir) {
  const std::string scene = root.choice("scene", {"deposition", "bed", "bunker_shot"});
  if (scene == "deposition") return make_deposition_scene(root, comm, case_dir);
  if (scene == "bunker_shot") return make_bunker_shot_scene(root, comm, case_dir);
  return make_bed_scene(root, comm, case_dir);
}

std::unique_ptr<Scene> make_scene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir) {
  const std::string scene = root.choice("scene", {"deposition", "bed", "bunker_shot", "flow", "coupled", "blast"});
  if (scene == "blast") return make_blast_scene(root, comm, case_dir);
  if (scene == "flow" || scene == "coupled") return make_flow_scene(root, comm, case_dir, scene == "coupled");
  return make_dem_scene(root, comm, case_dir);
}

}  // namespace tessera
