// SPDX-License-Identifier: MIT
// The loads the bodies put on the objects every rank holds alike, mesh walls (T14) and free spheres
// (T17): each rank lists its own contacts' reactions at the last evaluation, and sum() adds every
// rank's, in contact-key order, into each target on every rank. The same bits whatever the
// decomposition: a pivot's equation of motion and a free sphere's kick need the whole load.
#pragma once
#include <mpi.h>

#include <vector>

#include "core/vec3.hpp"
#include "solid/contact_history.hpp"
#include "solid/free_spheres.hpp"
#include "solid/mesh_walls.hpp"

namespace tessera {

class ReplicatedLoads {
 public:
  // Before an evaluation: no contacts listed; the targets' sums are stale until sum().
  void clear() { list_.clear(), pending_ = true; }
  // One contact's reaction on target (a mesh index, or the number of meshes + a free sphere's):
  // force, and moment (a mesh: about its origin; a sphere: about its centre).
  void add(PairKey key, std::size_t target, const Vec3& force, const Vec3& moment) {
    list_.insert(list_.end(), {static_cast<double>(key >> 32), static_cast<double>(key & 0xffffffffULL),
                               static_cast<double>(target), force.x, force.y, force.z, moment.x, moment.y, moment.z});
  }
  // Collective, once per evaluation (later calls do nothing): every rank's contacts added to the
  // meshes' force and moment and the spheres' force and torque, in key order.
  void sum(MPI_Comm comm, std::vector<MeshWall>& meshes, std::vector<FreeSphere>& spheres);

 private:
  std::vector<double> list_;  // per contact: key (2 x 32 bits), target, force, moment
  bool pending_ = false;
};

}  // namespace tessera
