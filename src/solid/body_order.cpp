// SPDX-License-Identifier: MIT
#include "solid/body_order.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

#include "core/morton.hpp"

namespace tessera {

void sort_owned_by_order(ParticleStore& p) {
  auto by_order = [&](std::size_t a, std::size_t b) { return p.order[a] < p.order[b]; };
  std::vector<std::size_t> perm(p.owned);
  std::iota(perm.begin(), perm.end(), std::size_t{0});
  if (std::is_sorted(perm.begin(), perm.end(), by_order)) return;
  std::sort(perm.begin(), perm.end(), by_order);
  std::vector<double> buf;
  buf.reserve(static_cast<std::size_t>(p.packed_size()) * p.owned);
  for (const auto i : perm) p.pack(i, buf);
  const std::size_t owned = p.owned, stride = static_cast<std::size_t>(p.packed_size());
  p.resize(0);
  for (std::size_t k = 0; k < owned; ++k) p.unpack_append(&buf[k * stride]);
  p.owned = owned;
  p.ghosts = 0;
}

void assign_morton_order(ParticleStore& p, const Decomposition& decomp) {
  // Every body's Morton code in the global box, sorted globally with the id breaking ties; a body's
  // key is its rank in that sort. Gathered on rank 0: 16 bytes per body.
  MPI_Comm comm = decomp.comm();
  const Vec3 lo = decomp.global_lo(), hi = decomp.global_hi();
  std::vector<std::uint64_t> mine(2 * p.owned);
  for (std::size_t i = 0; i < p.owned; ++i) {
    mine[2 * i] = morton(Vec3{p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]}, lo, hi);
    mine[2 * i + 1] = static_cast<std::uint64_t>(p.id[i]);
  }
  int size = 1, rank = 0, n = static_cast<int>(mine.size());
  MPI_Comm_size(comm, &size);
  MPI_Comm_rank(comm, &rank);
  std::vector<int> counts(size), displs(size, 0), half_counts(size), half_displs(size, 0);
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  std::vector<std::uint64_t> all;
  std::vector<std::int64_t> keys;
  if (rank == 0) {
    for (int r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
    for (int r = 0; r < size; ++r) half_counts[r] = counts[r] / 2, half_displs[r] = displs[r] / 2;
    all.resize(static_cast<std::size_t>(displs[size - 1] + counts[size - 1]));
  }
  MPI_Gatherv(mine.data(), n, MPI_UINT64_T, all.data(), counts.data(), displs.data(), MPI_UINT64_T, 0, comm);
  if (rank == 0) {
    const std::size_t total = all.size() / 2;
    std::vector<std::size_t> perm(total);
    std::iota(perm.begin(), perm.end(), std::size_t{0});
    std::sort(perm.begin(), perm.end(), [&](std::size_t a, std::size_t b) {
      return all[2 * a] != all[2 * b] ? all[2 * a] < all[2 * b] : all[2 * a + 1] < all[2 * b + 1];
    });
    keys.resize(total);
    for (std::size_t k = 0; k < total; ++k) keys[perm[k]] = static_cast<std::int64_t>(k);
  }
  std::vector<std::int64_t> my_keys(p.owned);
  MPI_Scatterv(keys.data(), half_counts.data(), half_displs.data(), MPI_INT64_T, my_keys.data(),
               static_cast<int>(p.owned), MPI_INT64_T, 0, comm);
  for (std::size_t i = 0; i < p.owned; ++i) p.order[i] = my_keys[i];
}

}  // namespace tessera
