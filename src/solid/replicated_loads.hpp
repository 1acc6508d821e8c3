// SPDX-License-Identifier: MIT
// The loads the bodies put on the objects every rank holds alike, mesh walls (T14) and free spheres
// (T17): each rank adds its own contacts' reactions at the last evaluation into exact sums
// (core/exact_sum.hpp), and sum() adds every rank's into each target on every rank, in one
// all-reduce. The same bits whatever the decomposition or the order of the contacts: a pivot's
// equation of motion and a free sphere's kick need the whole load.
#pragma once
#include <mpi.h>

#include <vector>

#include "core/exact_sum.hpp"
#include "core/vec3.hpp"
#include "solid/free_spheres.hpp"
#include "solid/mesh_walls.hpp"

namespace tessera {

class ReplicatedLoads {
 public:
  // Before an evaluation: nothing added; the targets' sums are stale until sum().
  void clear() {
    for (auto& s : sums_) s = ExactSum();
    pending_ = true;
  }
  // One contact's reaction on target (a mesh index, or the number of meshes + a free sphere's):
  // force, and moment (a mesh: about its origin; a sphere: about its centre).
  void add(std::size_t target, const Vec3& force, const Vec3& moment) {
    if (sums_.size() < 6 * (target + 1)) sums_.resize(6 * (target + 1));
    ExactSum* s = &sums_[6 * target];
    s[0] += force.x, s[1] += force.y, s[2] += force.z;
    s[3] += moment.x, s[4] += moment.y, s[5] += moment.z;
  }
  // Collective, once per evaluation (later calls do nothing): every rank's contacts added to the
  // meshes' force and moment and the spheres' force and torque.
  void sum(MPI_Comm comm, std::vector<MeshWall>& meshes, std::vector<FreeSphere>& spheres);

 private:
  std::vector<ExactSum> sums_;  // per target: force x, y, z, moment x, y, z
  bool pending_ = false;
};

}  // namespace tessera
