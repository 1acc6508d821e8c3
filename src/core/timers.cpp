// SPDX-License-Identifier: MIT
#include "core/timers.hpp"

#include <algorithm>
#include <set>

namespace tessera {

void PhaseTimers::add(const std::string& phase, double seconds) { seconds_[phase] += seconds; }

double PhaseTimers::total(const std::string& phase) const {
  const auto it = seconds_.find(phase);
  return it == seconds_.end() ? 0.0 : it->second;
}

std::vector<std::pair<std::string, PhaseTimers::Stats>> PhaseTimers::reduce(MPI_Comm comm) const {
  // Agree on the set of phase names first: ranks that never entered a phase report 0 for it.
  std::string mine;
  for (const auto& [name, s] : seconds_) mine += name + '\n';
  int len = static_cast<int>(mine.size()), size = 1;
  MPI_Comm_size(comm, &size);
  std::vector<int> lens(size), displs(size, 0);
  MPI_Allgather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, comm);
  for (int i = 1; i < size; ++i) displs[i] = displs[i - 1] + lens[i - 1];
  std::string all(displs[size - 1] + lens[size - 1], '\0');
  MPI_Allgatherv(mine.data(), len, MPI_CHAR, all.data(), lens.data(), displs.data(), MPI_CHAR, comm);
  std::set<std::string> names;
  for (std::size_t start = 0, end; (end = all.find('\n', start)) != std::string::npos; start = end + 1)
    names.insert(all.substr(start, end - start));

  std::vector<std::pair<std::string, Stats>> out;
  for (const auto& name : names) {
    const double t = total(name);
    Stats s;
    s.per_rank.resize(static_cast<std::size_t>(size));
    MPI_Allgather(&t, 1, MPI_DOUBLE, s.per_rank.data(), 1, MPI_DOUBLE, comm);
    s.min = *std::min_element(s.per_rank.begin(), s.per_rank.end());
    s.max = *std::max_element(s.per_rank.begin(), s.per_rank.end());
    for (const double r : s.per_rank) s.avg += r;
    s.avg /= size;
    out.emplace_back(name, s);
  }
  return out;
}

}  // namespace tessera
