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

ElementWork element_work(const BondedBlock& block, const std::vector<int>& level, const std::vector<char>& broken,
                         const std::vector<std::array<int, 2>>& contacts) {
  ElementWork w;
  w.level = level;
  w.bond.resize(block.bonds.size());
  w.bond_level.resize(block.bonds.size());
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    const auto i = static_cast<std::size_t>(block.bonds[b].master), j = static_cast<std::size_t>(block.bonds[b].slave);
    const int k = std::max(level[i], level[j]);
    w.bond_level[b] = k;
    if (!broken.empty() && broken[b]) continue;  // no work (its edge stays in METIS's graph, weightless)
    w.bond[b] = kBondCostPerUpdate * std::ldexp(1.0, k);
    w.level[i] = std::max(w.level[i], k), w.level[j] = std::max(w.level[j], k);  // kicked at its finest pair's level
  }
  w.contact = contacts;
  w.contact_level.resize(contacts.size());
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    const auto i = static_cast<std::size_t>(contacts[c][0]), j = static_cast<std::size_t>(contacts[c][1]);
    const int k = std::max(level[i], level[j]);
    w.contact_level[c] = k;
    w.level[i] = std::max(w.level[i], k), w.level[j] = std::max(w.level[j], k);
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

// METIS's vertex weights, `constraints` per element (element-major). A vertex carries its updates
// and half of each of its bonds (the other half is its partner's).
struct VertexWeights {
  std::size_t constraints = 1;
  std::vector<double> weight;
};

// The macro step's sum: one constraint (bond halves rounded as the edge weights are, to tenths).
VertexWeights sum_weights(const BondedBlock& block, const ElementWork& work) {
  VertexWeights w{1, work.element};
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    const double half = 0.05 * static_cast<double>(std::lround(10 * work.bond[b]));
    w.weight[static_cast<std::size_t>(block.bonds[b].master)] += half;
    w.weight[static_cast<std::size_t>(block.bonds[b].slave)] += half;
  }
  for (std::size_t c = 0; c < work.contact.size(); ++c) {
    const double half = 0.5 * kContactCostPerUpdate * std::ldexp(1.0, work.contact_level[c]);
    w.weight[static_cast<std::size_t>(work.contact[c][0])] += half, w.weight[static_cast<std::size_t>(work.contact[c][1])] += half;
  }
  return w;
}

// One constraint per level f: the vertex's work at a sub-step where the levels >= f are due (an
// update, and half an evaluation of each bond as fine as f). part_level_work sums the same.
VertexWeights level_weights(const BondedBlock& block, const ElementWork& work) {
  const std::size_t n = block.size(), nc = static_cast<std::size_t>(work_levels(work));
  VertexWeights w{nc, std::vector<double>(n * nc, 0.0)};
  for (std::size_t e = 0; e < n; ++e)
    for (std::size_t f = 0; f <= static_cast<std::size_t>(work.level[e]); ++f) w.weight[e * nc + f] += 1.0;
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    const auto i = static_cast<std::size_t>(block.bonds[b].master), j = static_cast<std::size_t>(block.bonds[b].slave);
    if (work.bond[b] == 0) continue;  // broken
    for (std::size_t f = 0; f <= static_cast<std::size_t>(work.bond_level[b]); ++f)
      w.weight[i * nc + f] += 0.5 * kBondCostPerUpdate, w.weight[j * nc + f] += 0.5 * kBondCostPerUpdate;
  }
  for (std::size_t c = 0; c < work.contact.size(); ++c) {
    const auto i = static_cast<std::size_t>(work.contact[c][0]), j = static_cast<std::size_t>(work.contact[c][1]);
    for (std::size_t f = 0; f <= static_cast<std::size_t>(work.contact_level[c]); ++f)
      w.weight[i * nc + f] += 0.5 * kContactCostPerUpdate, w.weight[j * nc + f] += 0.5 * kContactCostPerUpdate;
  }
  return w;
}

VertexWeights vertex_weights(const BondedBlock& block, const ElementWork& work, bool per_level) {
  return per_level && work_levels(work) > 1 ? level_weights(block, work) : sum_weights(block, work);
}

// The element graph in CSR form (elements joined by their bonds), edge weights in tenths of an
// update: built once for METIS's candidates.
struct ElementGraph {
  std::vector<idx_t> xadj, adjncy, adjwgt;
};

ElementGraph element_graph(const BondedBlock& block, const ElementWork& work) {
  const std::size_t n = block.size();
  std::vector<idx_t> degree(n + 1, 0);
  for (const BondGeometry& g : block.bonds) ++degree[static_cast<std::size_t>(g.master) + 1], ++degree[static_cast<std::size_t>(g.slave) + 1];
  std::vector<idx_t> xadj(n + 1, 0);
  for (std::size_t e = 0; e < n; ++e) xadj[e + 1] = xadj[e] + degree[e + 1];
  std::vector<idx_t> adjncy(static_cast<std::size_t>(xadj[n])), adjwgt(adjncy.size());
  std::vector<idx_t> fill(xadj.begin(), xadj.end() - 1);
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    const auto i = static_cast<std::size_t>(block.bonds[b].master), j = static_cast<std::size_t>(block.bonds[b].slave);
    const auto wb = std::max<idx_t>(1, static_cast<idx_t>(std::lround(10 * work.bond[b])));
    adjncy[static_cast<std::size_t>(fill[i])] = static_cast<idx_t>(j), adjwgt[static_cast<std::size_t>(fill[i]++)] = wb;
    adjncy[static_cast<std::size_t>(fill[j])] = static_cast<idx_t>(i), adjwgt[static_cast<std::size_t>(fill[j]++)] = wb;
  }
  return {std::move(xadj), std::move(adjncy), std::move(adjwgt)};
}

std::vector<int> metis_parts(const BondedBlock& block, const ElementWork& work, ElementGraph& graph, int parts,
                             bool per_level, bool weighted_tolerances = false) {
  const std::size_t n = block.size();
  if (parts == 1) return std::vector<int>(n, 0);
  const VertexWeights w = vertex_weights(block, work, per_level);
  const std::size_t nc = w.constraints;
  std::vector<idx_t> vwgt(n * nc);
  for (std::size_t k = 0; k < n * nc; ++k) vwgt[k] = static_cast<idx_t>(std::lround(10 * w.weight[k]));
  idx_t nv = static_cast<idx_t>(n), ncon = static_cast<idx_t>(nc), np = parts, cut = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;      // the same partition in every run
  options[METIS_OPTION_UFACTOR] = 10;  // parts within 1 % of the mean weight
  std::vector<idx_t> part(n, 0);
  // Per-level tolerances: each constraint's share of the sub-steps' time (its sub-steps' count times
  // its work) against the largest share; the largest kept to 1 %, a constraint of a tenth of it to
  // 10 %, none looser than 50 % (METIS then spends its freedom on the sub-steps that cost).
  std::vector<real_t> ubvec;
  if (weighted_tolerances && nc > 1) {
    std::vector<double> share(nc, 0.0);
    for (std::size_t f = 0; f < nc; ++f) {
      double total = 0;
      for (std::size_t e = 0; e < n; ++e) total += w.weight[e * nc + f];
      share[f] = (f == 0 ? 1.0 : std::ldexp(1.0, static_cast<int>(f) - 1)) * total;
    }
    const double top = *std::max_element(share.begin(), share.end());
    for (std::size_t f = 0; f < nc; ++f)
      ubvec.push_back(static_cast<real_t>(1.0 + std::min(0.5, 0.01 * top / std::max(share[f], 1e-300))));
  }
  const int status = METIS_PartGraphKway(&nv, &ncon, graph.xadj.data(), graph.adjncy.data(), vwgt.data(), nullptr, graph.adjwgt.data(),
                                         &np, nullptr, ubvec.empty() ? nullptr : ubvec.data(), options, &cut, part.data());
  if (status != METIS_OK)
    throw InputError("blast.partition", "metis",
                     "a block METIS can split into " + std::to_string(parts) + " parts (METIS status " +
                         std::to_string(status) + ")");
  return {part.begin(), part.end()};
}

}  // namespace

void refine_by_substeps(const BondedBlock& block, const ElementWork& work, std::vector<int>& part, int parts) {
  const std::size_t n = block.size(), nl = static_cast<std::size_t>(work_levels(work));
  if (parts < 2 || n == 0) return;
  // Each element's links that carry work (intact bonds, listed pairs): partner, level, cost a row.
  struct Link {
    int other, level;
    double cost;
  };
  std::vector<std::size_t> first(n + 1, 0);
  auto each_link = [&](auto&& fn) {
    for (std::size_t b = 0; b < block.bonds.size(); ++b)
      if (work.bond[b] != 0) fn(block.bonds[b].master, block.bonds[b].slave, work.bond_level[b], kBondCostPerUpdate);
    for (std::size_t c = 0; c < work.contact.size(); ++c)
      fn(work.contact[c][0], work.contact[c][1], work.contact_level[c], kContactCostPerUpdate);
  };
  each_link([&](int i, int j, int, double) { ++first[static_cast<std::size_t>(i) + 1], ++first[static_cast<std::size_t>(j) + 1]; });
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<Link> links(first[n]);
  {
    std::vector<std::size_t> fill(first.begin(), first.end() - 1);
    each_link([&](int i, int j, int level, double cost) {
      links[fill[static_cast<std::size_t>(i)]++] = {j, level, cost};
      links[fill[static_cast<std::size_t>(j)]++] = {i, level, cost};
    });
  }
  // The finest row each element's work reaches (its update or a link's).
  std::vector<std::size_t> reach(n);
  for (std::size_t e = 0; e < n; ++e) {
    reach[e] = static_cast<std::size_t>(work.level[e]);
    for (std::size_t l = first[e]; l < first[e + 1]; ++l) reach[e] = std::max(reach[e], static_cast<std::size_t>(links[l].level));
  }
  auto P = [&](int e) { return static_cast<std::size_t>(part[static_cast<std::size_t>(e)]); };
  std::vector<std::vector<double>> W = part_level_work(block, work, part, parts);
  // Each kind's sub-steps a macro step (substep_time's c_f) and, for the squares below, the same
  // over the row's mean at the start: a kind's squares then weigh as its share of the step's time,
  // not as the square of its work (the coarse rows' would drown the fine ones').
  std::vector<double> weight(nl), square_weight(nl);
  for (std::size_t f = 0; f < nl; ++f) {
    weight[f] = f == 0 ? 1.0 : std::ldexp(1.0, static_cast<int>(f) - 1);
    const double mean = std::accumulate(W[f].begin(), W[f].end(), 0.0) / parts;
    square_weight[f] = mean > 0 ? weight[f] / mean : 0.0;
  }
  // Each part's count of elements and its elements linked to another part (the candidates), with
  // every element's place in its part's list.
  const auto np = static_cast<std::size_t>(parts);
  std::vector<std::size_t> count(np, 0);
  std::vector<std::vector<int>> border(np);
  std::vector<std::size_t> slot(n, 0);
  constexpr std::size_t kNone = ~std::size_t{0};
  std::fill(slot.begin(), slot.end(), kNone);
  auto set_border = [&](int e) {
    const auto k = static_cast<std::size_t>(e);
    std::size_t out = 0;
    for (std::size_t l = first[k]; l < first[k + 1]; ++l) out += P(links[l].other) != P(e);
    auto& list = border[P(e)];
    if (out > 0 && slot[k] == kNone) slot[k] = list.size(), list.push_back(e);
    if (out == 0 && slot[k] != kNone) {
      const int last = list.back();
      list[slot[k]] = last, slot[static_cast<std::size_t>(last)] = slot[k];
      list.pop_back(), slot[k] = kNone;
    }
  };
  for (std::size_t e = 0; e < n; ++e) ++count[static_cast<std::size_t>(part[e])], set_border(static_cast<int>(e));
  // A move of e from a to b: a stops doing e's updates and the links' work that b or the partner's
  // part does not share with it (a link is worked on both its parts); b starts doing them.
  std::vector<double> dA(nl), dB(nl);
  auto deltas = [&](int e, std::size_t a, std::size_t b) {
    const auto k = static_cast<std::size_t>(e);
    // Each change at its level first, then summed down the rows (a level's work is due at every
    // coarser kind's sub-step too).
    std::fill(dA.begin(), dA.end(), 0.0), std::fill(dB.begin(), dB.end(), 0.0);
    const auto level = static_cast<std::size_t>(work.level[k]);
    dA[level] = -1.0, dB[level] = 1.0;
    for (std::size_t l = first[k]; l < first[k + 1]; ++l) {
      const std::size_t q = P(links[l].other), f = static_cast<std::size_t>(links[l].level);
      if (q != a) dA[f] -= links[l].cost;
      if (q != b) dB[f] += links[l].cost;
    }
    for (std::size_t f = nl - 1; f-- > 0;) dA[f] += dA[f + 1], dB[f] += dB[f + 1];
  };
  // Moves e from its part to b: the lists, counts and rows follow.
  auto apply_move = [&](int e, std::size_t b) {
    const std::size_t a = P(e);
    deltas(e, a, b);
    for (std::size_t f = 0; f < nl; ++f) W[f][a] += dA[f], W[f][b] += dB[f];
    const auto k = static_cast<std::size_t>(e);
    if (slot[k] != kNone) {  // out of a's candidates, into b's
      auto& list = border[a];
      const int last = list.back();
      list[slot[k]] = last, slot[static_cast<std::size_t>(last)] = slot[k];
      list.pop_back(), slot[k] = kNone;
    }
    part[k] = static_cast<int>(b), --count[a], ++count[b];
    set_border(e);
    for (std::size_t l = first[k]; l < first[k + 1]; ++l) set_border(links[l].other);
  };
  std::vector<std::size_t> targets;
  auto linked_parts = [&](int e) {
    targets.clear();
    const auto k = static_cast<std::size_t>(e);
    for (std::size_t l = first[k]; l < first[k + 1]; ++l) {
      const std::size_t q = P(links[l].other);
      if (q != P(e) && std::find(targets.begin(), targets.end(), q) == targets.end()) targets.push_back(q);
    }
  };
  const std::size_t max_moves = 4 * n;
  std::vector<std::array<std::size_t, 3>> top(nl);  // each row's three busiest parts
  std::vector<std::pair<std::size_t, std::size_t>> sources;  // (part, the coarsest row it is busiest in)
  for (std::size_t move = 0; move < max_moves; ++move) {
    double T = 0;
    sources.clear();
    for (std::size_t f = 0; f < nl; ++f) {
      std::array<std::size_t, 3> t{kNone, kNone, kNone};
      for (std::size_t p = 0; p < np; ++p) {
        auto above = [&](std::size_t q) { return q == kNone || W[f][p] > W[f][q]; };
        if (above(t[0])) t = {p, t[0], t[1]};
        else if (above(t[1])) t = {t[0], p, t[1]};
        else if (above(t[2])) t[2] = p;
      }
      top[f] = t;
      T += weight[f] * W[f][t[0]];
      // A row's busiest part, with the coarsest row it is busiest in: a move that shortens the step
      // lowers it there or finer, so the element's work reaches that row.
      auto at = std::find_if(sources.begin(), sources.end(), [&](const auto& s) { return s.first == t[0]; });
      if (at == sources.end()) sources.push_back({t[0], f});
    }
    // The best move out of a row's busiest part (only such a move can shorten the step): the
    // shortest step, then the least sum of the rows' squared work (it falls as work goes from a
    // busier part to a less busy one; where two parts tie as a row's busiest, this moves work off
    // one of them first).
    double best_T = T, best_S = 0;
    int best_e = -1;
    std::size_t best_b = 0;
    for (const auto& [a, row] : sources) {
      if (count[a] < 2) continue;  // no part left empty
      for (int e : border[a]) {
        if (reach[static_cast<std::size_t>(e)] < row) continue;
        linked_parts(e);
        for (std::size_t b : targets) {
          deltas(e, a, b);
          double T2 = 0, S2 = 0;
          for (std::size_t f = 0; f < nl; ++f) {
            const double wa = W[f][a] + dA[f], wb = W[f][b] + dB[f];
            double rest = 0;
            for (std::size_t q : top[f])
              if (q != kNone && q != a && q != b) {
                rest = W[f][q];
                break;
              }
            T2 += weight[f] * std::max({wa, wb, rest});
            S2 += square_weight[f] * (wa * wa - W[f][a] * W[f][a] + wb * wb - W[f][b] * W[f][b]);
          }
          if (T2 < best_T || (T2 == best_T && S2 < best_S)) best_T = T2, best_S = S2, best_e = e, best_b = b;
        }
      }
    }
    if (best_e < 0) break;  // no move shortens the step or evens the work
    apply_move(best_e, best_b);
  }
}

std::vector<int> partition_elements(const BondedBlock& block, const ElementWork& work, Partition how, const Vec3& lo,
                                    const Vec3& hi, std::array<int, 3> dims) {
  const int parts = dims[0] * dims[1] * dims[2];
  if (static_cast<std::size_t>(parts) > block.size())
    throw InputError("ranks", std::to_string(parts), "at most one rank per element (" + std::to_string(block.size()) + ")");
  if (how == Partition::metis) {
    // One constraint per level, or the sum alone, or one constraint per level with tolerances by
    // the levels' shares of the sub-steps' time, whichever gives the shorter macro step (few
    // elements per rank cannot meet every constraint: the seed's 958 on 16 ranks; many constraints
    // with equal tolerances can leave the costly ones unmet: the fine mesh on 64 ranks, 1.121
    // with equal tolerances, 1.045 weighted).
    ElementGraph graph = element_graph(block, work);
    std::vector<int> per_level = metis_parts(block, work, graph, parts, true);
    if (work_levels(work) == 1) return per_level;  // one level: the sum was the only constraint
    std::vector<int> sum = metis_parts(block, work, graph, parts, false);
    const double t_level = substep_time(part_level_work(block, work, per_level, parts));
    const double t_sum = substep_time(part_level_work(block, work, sum, parts));
    // The weighted tolerances where ranks hold many elements (on a few dozen a rank METIS's loose
    // constraints can leave a part empty); taken where no part is empty and the step is shorter.
    if (block.size() >= std::size_t{100} * static_cast<std::size_t>(parts)) {
      std::vector<int> weighted = metis_parts(block, work, graph, parts, true, true);
      std::vector<char> used(static_cast<std::size_t>(parts), 0);
      for (int p : weighted) used[static_cast<std::size_t>(p)] = 1;
      const double t_weighted = substep_time(part_level_work(block, work, weighted, parts));
      if (std::count(used.begin(), used.end(), 0) == 0 && t_weighted < std::min(t_level, t_sum)) {
        refine_by_substeps(block, work, weighted, parts);
        return weighted;
      }
    }
    std::vector<int>& chosen = t_level <= t_sum ? per_level : sum;
    refine_by_substeps(block, work, chosen, parts);
    return chosen;
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
  for (std::size_t c = 0; c < work.contact.size(); ++c) {
    const int pi = part[static_cast<std::size_t>(work.contact[c][0])], pj = part[static_cast<std::size_t>(work.contact[c][1])];
    const double visits = kContactCostPerUpdate * std::ldexp(1.0, work.contact_level[c]);
    w[static_cast<std::size_t>(pi)] += visits;
    if (pj != pi) w[static_cast<std::size_t>(pj)] += visits;
  }
  return w;
}

int work_levels(const ElementWork& work) {
  int levels = 1;
  for (int k : work.level) levels = std::max(levels, k + 1);
  return levels;
}

std::vector<std::vector<double>> part_level_work(const BondedBlock& block, const ElementWork& work,
                                                 const std::vector<int>& part, int parts) {
  const auto nl = static_cast<std::size_t>(work_levels(work));
  std::vector<std::vector<double>> w(nl, std::vector<double>(static_cast<std::size_t>(parts), 0.0));
  for (std::size_t e = 0; e < block.size(); ++e)
    for (std::size_t f = 0; f <= static_cast<std::size_t>(work.level[e]); ++f) w[f][static_cast<std::size_t>(part[e])] += 1.0;
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    const int pi = part[static_cast<std::size_t>(block.bonds[b].master)], pj = part[static_cast<std::size_t>(block.bonds[b].slave)];
    if (work.bond[b] == 0) continue;  // broken
    for (std::size_t f = 0; f <= static_cast<std::size_t>(work.bond_level[b]); ++f) {
      w[f][static_cast<std::size_t>(pi)] += kBondCostPerUpdate;
      if (pj != pi) w[f][static_cast<std::size_t>(pj)] += kBondCostPerUpdate;
    }
  }
  for (std::size_t c = 0; c < work.contact.size(); ++c) {
    const int pi = part[static_cast<std::size_t>(work.contact[c][0])], pj = part[static_cast<std::size_t>(work.contact[c][1])];
    for (std::size_t f = 0; f <= static_cast<std::size_t>(work.contact_level[c]); ++f) {
      w[f][static_cast<std::size_t>(pi)] += kContactCostPerUpdate;
      if (pj != pi) w[f][static_cast<std::size_t>(pj)] += kContactCostPerUpdate;
    }
  }
  return w;
}

LevelHalo part_level_halo(const BondedBlock& block, const ElementWork& work, const std::vector<int>& part, int parts) {
  // (part sent to, element) once each, as build_halo lists them.
  std::vector<std::pair<int, int>> sent;
  for (const BondGeometry& g : block.bonds) {
    const int pi = part[static_cast<std::size_t>(g.master)], pj = part[static_cast<std::size_t>(g.slave)];
    if (pi == pj) continue;
    sent.push_back({pj, g.master}), sent.push_back({pi, g.slave});
  }
  std::sort(sent.begin(), sent.end());
  sent.erase(std::unique(sent.begin(), sent.end()), sent.end());
  LevelHalo h;
  const auto nl = static_cast<std::size_t>(work_levels(work));
  h.sent.assign(nl, std::vector<double>(static_cast<std::size_t>(parts), 0.0));
  std::vector<std::vector<char>> linked(static_cast<std::size_t>(parts), std::vector<char>(static_cast<std::size_t>(parts), 0));
  for (const auto& [to, e] : sent) {
    const int from = part[static_cast<std::size_t>(e)];
    linked[static_cast<std::size_t>(from)][static_cast<std::size_t>(to)] = 1;
    for (std::size_t f = 0; f <= static_cast<std::size_t>(work.level[static_cast<std::size_t>(e)]); ++f)
      h.sent[f][static_cast<std::size_t>(from)] += 1.0;
  }
  for (const auto& row : linked) h.neighbours.push_back(static_cast<int>(std::count(row.begin(), row.end(), 1)));
  return h;
}

std::vector<double> level_imbalance(const std::vector<std::vector<double>>& level_work) {
  std::vector<double> r;
  for (const auto& row : level_work) r.push_back(imbalance(row));
  return r;
}

namespace {

// sum_f c_f x_f over the levels' rows, x_f from `of` (the row's busiest rank or its mean).
template <class Of>
double over_substeps(const std::vector<std::vector<double>>& level_work, Of of) {
  double sum = 0;
  for (std::size_t f = 0; f < level_work.size(); ++f)
    if (!level_work[f].empty()) sum += (f == 0 ? 1.0 : std::ldexp(1.0, static_cast<int>(f) - 1)) * of(level_work[f]);
  return sum;
}

double busiest(const std::vector<double>& row) { return *std::max_element(row.begin(), row.end()); }
double mean(const std::vector<double>& row) {
  return std::accumulate(row.begin(), row.end(), 0.0) / static_cast<double>(row.size());
}

}  // namespace

double substep_time(const std::vector<std::vector<double>>& level_work) { return over_substeps(level_work, busiest); }

double substep_imbalance(const std::vector<std::vector<double>>& level_work) {
  const double m = over_substeps(level_work, mean);
  return m > 0 ? substep_time(level_work) / m : 1.0;
}

long cut_bonds(const BondedBlock& block, const std::vector<int>& part) {
  long n = 0;
  for (const BondGeometry& g : block.bonds) n += part[static_cast<std::size_t>(g.master)] != part[static_cast<std::size_t>(g.slave)];
  return n;
}

}  // namespace tessera
