// SPDX-License-Identifier: MIT
#include "solid/replicated_loads.hpp"

#include <algorithm>
#include <numeric>

#include "core/all_gather.hpp"

namespace tessera {

void ReplicatedLoads::sum(MPI_Comm comm, std::vector<MeshWall>& meshes, std::vector<FreeSphere>& spheres) {
  if (!pending_) return;
  pending_ = false;
  constexpr int stride = 9;
  const std::vector<double> all = all_gather_concat(comm, list_);
  const std::size_t n = all.size() / stride;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return all[a * stride] != all[b * stride] ? all[a * stride] < all[b * stride]
                                              : all[a * stride + 1] < all[b * stride + 1];
  });
  for (const auto c : order) {
    const double* r = &all[c * stride];
    const auto target = static_cast<std::size_t>(r[2]);
    if (target < meshes.size()) {
      MeshWall& m = meshes[target];
      m.force += Vec3{r[3], r[4], r[5]};
      m.moment += Vec3{r[6], r[7], r[8]};
    } else {
      FreeSphere& s = spheres[target - meshes.size()];
      s.force += Vec3{r[3], r[4], r[5]};
      s.torque += Vec3{r[6], r[7], r[8]};
    }
  }
}

}  // namespace tessera
