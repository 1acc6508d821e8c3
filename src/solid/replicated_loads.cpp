// SPDX-License-Identifier: MIT
#include "solid/replicated_loads.hpp"

namespace tessera {

void ReplicatedLoads::sum(MPI_Comm comm, std::vector<MeshWall>& meshes, std::vector<FreeSphere>& spheres) {
  if (!pending_) return;
  pending_ = false;
  sums_.resize(6 * (meshes.size() + spheres.size()));  // every rank the same length
  ExactSum::all_reduce(sums_, comm);
  for (std::size_t t = 0; t < meshes.size() + spheres.size(); ++t) {
    const ExactSum* s = &sums_[6 * t];
    const Vec3 force{s[0].value(), s[1].value(), s[2].value()}, moment{s[3].value(), s[4].value(), s[5].value()};
    if (t < meshes.size()) {
      meshes[t].force += force;
      meshes[t].moment += moment;
    } else {
      spheres[t - meshes.size()].force += force;
      spheres[t - meshes.size()].torque += moment;
    }
  }
}

}  // namespace tessera
