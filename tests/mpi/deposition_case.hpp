// SPDX-License-Identifier: MIT
// A small, violent deposition for parallel tests: 1088 grains fall at 100 g for a few thousand
// steps, so contacts form, slide and break, and bodies cross sub-domain faces in every direction.
#pragma once
#include <string>

namespace tessera::test {

inline const char* kViolentDeposition = R"(
scene: deposition
domain: {box_min: [0, 0, 0], box_max: [6 mm, 6 mm, 12 mm]}
solid:
  gravity: [0.5, -0.3, -981]
  steps_per_contact: 20
  neighbor_skin: 0.15 mm
  materials: {sand: {density: 2480}, wall: {density: 2480}}
  contact:
    law: hooke
    pairs:
      - {materials: [sand, sand], normal_stiffness: 2000, tangential_stiffness: 571.4, normal_damping_rate: 5.146e4, tangential_damping_rate: 2.573e4, friction: 0.4}
      - {materials: [sand, wall], normal_stiffness: 2000, tangential_stiffness: 571.4, normal_damping_rate: 5.146e4, tangential_damping_rate: 2.573e4, friction: 0.4}
  walls: [{type: box, min: [0, 0, 0], max: [6 mm, 6 mm, 12 mm], material: wall}]
deposition:
  material: sand
  diameter: 0.6 mm
  lattice_spacing: 0.7 mm
  jitter: 0.04 mm
  region_min: [0, 0, 0]
  region_max: [6 mm, 6 mm, 12 mm]
  settled_kinetic_energy: 1e-30
run: {end_time: 1.0, check_interval: 1 ms}
)";

// The same with spheroidal grains of the seed's size (24 contact spheres each, to stay quick): 128
// grains in random orientations, tumbling, so that contact-sphere pairs form and break between
// bodies on different ranks and bodies migrate with their per-sphere histories.
inline const char* kViolentShapedDeposition = R"(
scene: deposition
domain: {box_min: [0, 0, 0], box_max: [6 mm, 6 mm, 12 mm]}
solid:
  gravity: [200, -150, -981]   # sideways too: grains cross the x and y cuts
  steps_per_contact: 20
  neighbor_skin: 0.05 mm
  materials: {sand: {density: 2650}, wall: {density: 2650}}
  shapes:
    - name: grain
      spheroid: {semi_axes: [0.635 mm, 0.26 mm, 0.26 mm], rings: 5, segments: 9}
      contact_spheres: {count: 24, radius: 0.1 mm}
  contact:
    law: hooke
    pairs:
      - {materials: [sand, sand], normal_stiffness: 1e4, tangential_stiffness: 1e4, restitution: 0.5, friction: 0.6}
      - {materials: [sand, wall], normal_stiffness: 1e4, tangential_stiffness: 1e4, restitution: 0.5, friction: 0.6}
  walls: [{type: box, min: [0, 0, 0], max: [6 mm, 6 mm, 12 mm], material: wall}]
deposition:
  shape: grain
  material: sand
  lattice_spacing: 1.45 mm
  jitter: 0.05 mm
  region_min: [0, 0, 0]
  region_max: [6 mm, 6 mm, 12 mm]
  settled_kinetic_energy: 1e-30
run: {end_time: 1.0, check_interval: 1 ms}
)";

// The violent deposition onto triangle-mesh walls read from STL files: a V-shaped valley floor
// (concave: two contacts along its bottom) and a paddle turning about a pivot under the grains'
// impacts (tests/data). MESH_DIR is replaced by the test with the data directory.
inline const char* kMeshDepositionWalls = R"(
  walls:
    - {type: box, min: [0, 0, 0], max: [6 mm, 6 mm, 12 mm], material: wall}
    - {type: mesh, file: MESH_DIR/valley.stl, scale: 1e-3, material: wall, motion: {type: fixed}}
    - type: mesh
      file: MESH_DIR/paddle.stl
      scale: 1e-3
      material: wall
      motion: {type: pivot, pivot: [3 mm, 0, 7 mm], axis: [0, 1, 0], moment_of_inertia: 2e-10, angular_velocity: 3.0}
)";

inline std::string mesh_case() {
  // kViolentDeposition with its box plus the STL valley and pivoted paddle, grains starting above.
  std::string c = kViolentDeposition;
  const std::string walls = "  walls: [{type: box, min: [0, 0, 0], max: [6 mm, 6 mm, 12 mm], material: wall}]\n";
  std::string mesh = kMeshDepositionWalls;
  for (std::size_t at; (at = mesh.find("MESH_DIR")) != std::string::npos;)
    mesh.replace(at, 8, std::string(TESSERA_SOURCE_DIR) + "/tests/data");
  c.replace(c.find(walls), walls.size(), mesh.substr(1));
  c.replace(c.find("region_min: [0, 0, 0]"), 21, "region_min: [0, 0, 7.4 mm]");
  return c;
}

}  // namespace tessera::test
