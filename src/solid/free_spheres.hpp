// SPDX-License-Identifier: MIT
// Free spheres (T17): bodies far larger than the grains around them (the bunker shot's 43 mm ball
// among 0.6 mm grains). Putting one in the grain arrays would make the cell search and the ghost
// halo as wide as its diameter; instead every rank keeps the whole sphere, as it keeps the mesh
// walls:
//   - each rank finds its owned grains within reach of the sphere at each list rebuild and computes
//     those contacts with the body-body law (the material pair grain/sphere, m* and R* of the two);
//     the history travels with the grain like a mesh-wall spring;
//   - the reaction of every grain contact is summed in contact-key order on every rank (the same
//     bits whatever the decomposition);
//   - contacts with wall planes and mesh walls (the club) are computed on every rank alike, with
//     the wall law and the sphere's mass and radius; their reaction goes to the mesh;
//   - velocity Verlet with the grains; in plane mode a disc of the plane's thickness, moving in the
//     plane and turning about its normal.
// Free spheres do not touch each other.
#pragma once
#include <array>
#include <string>

#include "core/vec3.hpp"

namespace tessera {

struct FreeSphere {
  std::string key;  // case-file key, for messages and output
  int material = 0;
  double radius = 0, mass = 0, inertia = 0;
  Vec3 x, v, omega;
  Vec3 force, torque;         // contact load at the last evaluation (every rank)
  bool touches_wall = false;  // a wall plane or box touched it at the last evaluation
  Vec3 x_build;               // centre at the last list rebuild
};

}  // namespace tessera
