// SPDX-License-Identifier: MIT
// Which rank owns each element, and moving them during a run (issue 19; element_partition.hpp):
// the partition of a work map, the work now (the last macro step's levels, the intact bonds, the
// listed contact pairs), its imbalance on the owners now, and a repartition that carries the state
// over as a restart does (checkpoint, then restore on the new owners: the same bits).
#include <mpi.h>

#include <unordered_map>

#include "fracture/fracture_solver.hpp"

namespace tessera {

void FractureSolver::assign_owners() {
  // METIS's partition is made on rank 0 and sent: every rank must hold the same owners.
  const std::size_t n = block_.size();
  const bool metis = settings_.partition == Partition::metis;
  std::vector<int> part(n, 0);
  if (!metis || decomp_.rank() == 0)
    part = partition_elements(block_, work_, settings_.partition, decomp_.global_lo(), decomp_.global_hi(), decomp_.dims());
  if (metis && decomp_.size() > 1) MPI_Bcast(part.data(), static_cast<int>(n), MPI_INT, 0, decomp_.comm());
  owner_.resize(n);
  owned_by_rank_.assign(static_cast<std::size_t>(decomp_.size()), {});
  for (std::size_t e = 0; e < n; ++e) {
    int r = part[e];
    if (settings_.partition != Partition::metis) {  // a grid cell, x fastest: its rank in the Cartesian grid
      const auto& d = decomp_.dims();
      int c[3] = {r % d[0], (r / d[0]) % d[1], r / (d[0] * d[1])};
      MPI_Cart_rank(decomp_.comm(), c, &r);
    }
    owner_[e] = r;
    owned_by_rank_[static_cast<std::size_t>(r)].push_back(static_cast<int>(e));
  }
}

ElementWork FractureSolver::work_now(const ContactListState& list) const {
  // The last macro step's levels (every rank's alike), the intact bonds and every listed pair.
  std::unordered_map<long, int> element_of;
  for (const Sphere& s : spheres_) element_of[s.key] = s.element;
  std::vector<std::array<int, 2>> contacts;
  contacts.reserve(list.pairs.size());
  for (const auto& [ka, kb] : list.pairs) contacts.push_back({element_of.at(ka), element_of.at(kb)});
  const bool levels = settings_.stepping != Stepping::uniform && level_.size() == block_.size();
  return element_work(block_, levels ? level_ : std::vector<int>(block_.size(), 0), broken_, contacts);
}

FractureSolver::BalanceCheck FractureSolver::balance_check() const {
  BalanceCheck c;
  c.list = contact_list_state();
  c.work = work_now(c.list);
  c.imbalance = substep_imbalance(part_level_work(block_, c.work, owner_, decomp_.size()));
  return c;
}

double FractureSolver::rebalance(const BalanceCheck& check) {
  // As a restart would (checkpoint, then restore on the new owners): the owners' full state to
  // every rank, the contact list by sphere keys (the check's: the list state reads the list's own
  // build poses and pairs, which sync_state leaves alone), the dashpots' frozen orientations; then
  // the partition of the check's work, and the state restored on it. restore keeps the bits of an
  // uninterrupted run (BlastRestart), and no result depends on the owners.
  sync_state();
  const ContactListState& list = check.list;
  const std::vector<Quaternion> frozen = damping_frozen();
  work_ = check.work;
  assign_owners();
  const std::vector<Vec3> x = x_, v = v_, L = L_, F = F_, T = T_;
  const std::vector<Quaternion> q = q_;
  const std::vector<std::array<BondVertex, 3>> bonds = bond_state_;
  const std::vector<char> broken = broken_;
  restore(x, q, v, L, bonds, broken, list, F, T);
  frozen_q_ = frozen;
  damping_ = DampingWork{};  // every block made again at the frozen orientations (the same numbers)
  setup(false);
  return substep_imbalance(part_level_work(block_, work_, owner_, decomp_.size()));
}

}  // namespace tessera
