// SPDX-License-Identifier: MIT
// Every rank's vector, concatenated in rank order, on every rank (MPI_Allgather of the counts, then
// MPI_Allgatherv). Collective.
#pragma once
#include <mpi.h>

#include <cstdint>
#include <type_traits>
#include <vector>

namespace tessera {

template <class T>
std::vector<T> all_gather_concat(MPI_Comm comm, const std::vector<T>& mine) {
  static_assert(std::is_same_v<T, int> || std::is_same_v<T, long> || std::is_same_v<T, double>);
  MPI_Datatype type = std::is_same_v<T, int> ? MPI_INT : (std::is_same_v<T, long> ? MPI_LONG : MPI_DOUBLE);
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size == 1) return mine;
  const int n = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<std::size_t>(size)), displs(counts.size());
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  int total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) displs[r] = total, total += counts[r];
  std::vector<T> all(static_cast<std::size_t>(total));
  MPI_Allgatherv(mine.data(), n, type, all.data(), counts.data(), displs.data(), type, comm);
  return all;
}

}  // namespace tessera
