// SPDX-License-Identifier: MIT
#include "fracture/element_partition.hpp"

#include <metis.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "core/balance.hpp"
#include "core/errors.hpp"

namespace tessera {

Partition partition_from_name(const std::string& name) {
  if (name == "balanced") return Partition::balanced;
  if (name == "metis") return Partition::metis;
  if (name == "slabs") return Partition::slabs;
  throw InputError("blast.partition", name, "slabs, balanced or metis");
}

const char* partition_name(Partition p) {
  return p == Partition::metis ? "metis" : (p == Partition::balanced ? "balanced" : "slabs");
}

ElementWork element_work(const BondedBlock& block, const std::vector<int>& level) {
  ElementWork w;
  w.level = level;
  w.bond.resize(block.bonds.size());
  w.bond_level.resize(block.bonds.size());
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    const auto i = static_cast<std::size_t>(block.bonds[b].master), j = static_cast<std::size_t>(block.bonds[b].slave);
    const int k = std::max(level[i], level[j]);
    w.bond_level[b] = k;
    w.bond[b] = kBondCostPerUpdate * std::ldexp(1.0, k);
    w.level[i] = std::max(w.level[i], k), w.level[j] = std::max(w.level[j], k);  // kicked at its finest bond's level
  }
  w.element.resize(block.size());
  for (std::size_t e = 0; e < block.size(); ++e) w.element[e] = std::ldexp(1.0, level[e]);
  return w;
}

namespace {

std::vector<int> grid_parts(const BondedBlock& block, const CutPlanes& cuts, std::array<int, 3> dims) {
  std::vector<int> part(block.size());
  for (std::size_t e = 0; e < block.size(); ++e) part[e] = grid_cell(block.x0[e], dims, cuts);
  return part;
}

std::vector<int> metis_parts(const BondedBlock& block, const ElementWork& work, int parts, bool per_level) {
  const std::size_t n = block.size();
  if (parts == 1) return std::vector<int>(n, 0);
  // The element graph in CSR form; integer weights in tenths of an update.
  std::vector<idx_t> degree(n + 1, 0);
  for (const BondGeometry& g : block.bonds) ++degree[static_cast<std::size_t>(g.master) + 1], ++degree[static_cast<std::size_t>(g.slave) + 1];
  std::vector<idx_t> xadj(n + 1, 0);
  for (std::size_t e = 0; e < n; ++e) xadj[e + 1] = xadj[e] + degree[e + 1];
  std::vector<idx_t> adjncy(static_cast<std::size_t>(xadj[n])), adjwgt(adjncy.size()), vwgt(n);
  std::vector<idx_t> fill(xadj.begin(), xadj.end() - 1);
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    const auto i = static_cast<std::size_t>(block.bonds[b].master), j = static_cast<std::size_t>(block.bonds[b].slave);
    const auto wb = static_cast<idx_t>(std::lround(10 * work.bond[b]));
    adjncy[static_cast<std::size_t>(fill[i])] = static_cast<idx_t>(j), adjwgt[static_cast<std::size_t>(fill[i]++)] = wb;
    adjncy[static_cast<std::size_t>(fill[j])] = static_cast<idx_t>(i), adjwgt[static_cast<std::size_t>(fill[j]++)] = wb;
  }
  // A vertex carries its updates and half of each of its bonds (the other half is its partner's).
  // With levels, one constraint per level f: its work at a sub-step where the levels >= f are due
  // (an update, and half an evaluation of each bond as fine as f).
  int levels = 1;
  for (std::size_t e = 0; per_level && e < n; ++e) levels = std::max(levels, work.level[e] + 1);
  const auto nc = static_cast<std::size_t>(levels);
  std::vector<double> w(n * nc, 0.0);
  for (std::size_t e = 0; e < n; ++e) {
    if (nc == 1) w[e] = work.element[e];
    for (std::size_t f = 0; nc > 1 && f <= static_cast<std::size_t>(work.level[e]); ++f) w[e * nc + f] += 1.0;
  }
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    const auto i = static_cast<std::size_t>(block.bonds[b].master), j = static_cast<std::size_t>(block.bonds[b].slave);
    if (nc == 1) {
      const double half = 0.05 * static_cast<double>(std::lround(10 * work.bond[b]));
      w[i] += half, w[j] += half;
    }
    for (std::size_t f = 0; nc > 1 && f <= static_cast<std::size_t>(work.bond_level[b]); ++f)
      w[i * nc + f] += 0.5 * kBondCostPerUpdate, w[j * nc + f] += 0.5 * kBondCostPerUpdate;
  }
  vwgt.resize(n * nc);
  for (std::size_t k = 0; k < n * nc; ++k) vwgt[k] = static_cast<idx_t>(std::lround(10 * w[k]));
  idx_t nv = static_cast<idx_t>(n), ncon = static_cast<idx_t>(nc), np = parts, cut = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;      // the same partition in every run
  options[METIS_OPTION_UFACTOR] = 10;  // parts within 1 % of the mean weight
  std::vector<idx_t> part(n, 0);
  const int status = METIS_PartGraphKway(&nv, &ncon, xadj.data(), adjncy.data(), vwgt.data(), nullptr, adjwgt.data(),
                                         &np, nullptr, nullptr, options, &cut, part.data());
  if (status != METIS_OK)
    throw InputError("blast.partition", "metis",
                     "a block METIS can split into " + std::to_string(parts) + " parts (METIS status " +
                         std::to_string(status) + ")");
  return {part.begin(), part.end()};
}

}  // namespace

std::vector<int> partition_elements(const BondedBlock& block, const ElementWork& work, Partition how, const Vec3& lo,
                                    const Vec3& hi, std::array<int, 3> dims) {
  const int parts = dims[0] * dims[1] * dims[2];
  if (static_cast<std::size_t>(parts) > block.size())
    throw InputError("ranks", std::to_string(parts), "at most one rank per element (" + std::to_string(block.size()) + ")");
  if (how == Partition::metis) {
    // One constraint per level where that keeps the macro step's sum within 5 % (few elements per
    // rank cannot balance every level: the seed's 958 on 16 ranks gave 1.17); else the sum alone.
    std::vector<int> part = metis_parts(block, work, parts, true);
    const std::vector<double> w = part_work(block, work, part, parts);
    const double mean = std::accumulate(w.begin(), w.end(), 0.0) / parts;
    if (*std::max_element(w.begin(), w.end()) <= 1.05 * mean) return part;
    return metis_parts(block, work, parts, false);
  }
  if (how == Partition::slabs) return grid_parts(block, equal_cuts(lo, hi, dims), dims);
  std::vector<WorkSample> samples(block.size());
  for (std::size_t e = 0; e < block.size(); ++e) samples[e] = {block.x0[e], work.element[e]};
  // Each bond's work at its master's centroid (a cut bond's second evaluation is not known yet).
  for (std::size_t b = 0; b < block.bonds.size(); ++b) samples[static_cast<std::size_t>(block.bonds[b].master)].weight += work.bond[b];
  return grid_parts(block, balanced_cuts(samples, lo, hi, dims), dims);
}

std::vector<double> part_work(const BondedBlock& block, const ElementWork& work, const std::vector<int>& part,
                              int parts) {
  std::vector<double> w(static_cast<std::size_t>(parts), 0.0);
  for (std::size_t e = 0; e < block.size(); ++e) w[static_cast<std::size_t>(part[e])] += work.element[e];
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    const int pi = part[static_cast<std::size_t>(block.bonds[b].master)], pj = part[static_cast<std::size_t>(block.bonds[b].slave)];
    w[static_cast<std::size_t>(pi)] += work.bond[b];
    if (pj != pi) w[static_cast<std::size_t>(pj)] += work.bond[b];
  }
  return w;
}

long cut_bonds(const BondedBlock& block, const std::vector<int>& part) {
  long n = 0;
  for (const BondGeometry& g : block.bonds) n += part[static_cast<std::size_t>(g.master)] != part[static_cast<std::size_t>(g.slave)];
  return n;
}

}  // namespace tessera
