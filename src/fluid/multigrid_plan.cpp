// SPDX-License-Identifier: MIT
#include "fluid/multigrid_plan.hpp"

#include <algorithm>
#include <numeric>

namespace tessera {
namespace {

constexpr long kCoarsestCells = 256;   // stop coarsening below this many cells in all
constexpr long kTwoLayersFace = 2048;  // two ghost layers on a level whose faces are at most this

// The aggregates of c cells from cell `first` along a direction that coarsens: pairs; an odd run's
// last cell alone, or, where it is narrower than the cell before it (what is left of a finer
// level's single cell), with that pair (a triple), so that no coarser level keeps a sliver.
int pair_count(int c, int first, const std::vector<int>& span) {
  const bool triple = c % 2 == 1 && c >= 3 && span[std::size_t(first + c - 1)] < span[std::size_t(first + c - 2)];
  return triple ? c / 2 : (c + 1) / 2;
}

}  // namespace

std::vector<MultigridLevelPlan> plan_multigrid(std::array<std::vector<int>, 3> own, const std::array<bool, 3>& periodic,
                                               int ghost_layers, bool level_pairs) {
  std::vector<MultigridLevelPlan> plan;
  std::array<int, 3> n{};
  for (int d = 0; d < 3; ++d) n[d] = std::accumulate(own[d].begin(), own[d].end(), 0);
  std::array<std::vector<int>, 3> fine_start, parts;  // of the level being made
  std::array<bool, 3> merged{}, crosses{};
  while (true) {
    MultigridLevelPlan L;
    L.n = n;
    L.blocks = own;
    L.fine_start = fine_start;
    L.merged = merged;
    L.crosses = crosses;
    L.parts = parts;
    const auto procs = L.procs();
    for (int d = 0; d < 3; ++d) L.halo = L.halo || procs[d] > 1 || periodic[d];
    // Two ghost layers where every block along each direction with a neighbour (a rank, or a
    // periodic image) is at least 2 cells across: the layers sent are owned cells. Only where an
    // exchange is latency-bound: every rank's face across a split direction at most
    // kTwoLayersFace cells (a layer of 2,048 cells is 16 kB, about what this host's point-to-point
    // bandwidth moves in one latency, 1.9 us x 9.8 GB/s; docs/performance.md): on large faces the
    // second layer's bytes and the ghost layer's updates cost more than the latency saved (the
    // V-cycle 3-5 % slower on 2 ranks of the paper drop's grid).
    if (ghost_layers >= 2 && L.halo) {
      L.layers = 2;
      for (int d = 0; d < 3; ++d)
        if (procs[d] > 1 || periodic[d]) {
          for (int c : own[d]) L.layers = c < 2 ? 1 : L.layers;
          const auto& a = own[(d + 1) % 3];
          const auto& b = own[(d + 2) % 3];
          const long face = long(*std::max_element(a.begin(), a.end())) * long(*std::max_element(b.begin(), b.end()));
          if (face > kTwoLayersFace) L.layers = 1;
        }
    }
    for (int d = 0; d < 3; ++d)
      if (plan.empty()) {
        L.span[d].assign(std::size_t(n[d]), 1);
      } else {
        for (int I = 0; I < n[d]; ++I) {
          int w = 0;
          for (int i = fine_start[d][std::size_t(I)]; i < fine_start[d][std::size_t(I) + 1]; ++i)
            w += plan.back().span[d][std::size_t(i)];
          L.span[d].push_back(w);
        }
      }
    plan.push_back(std::move(L));
    if (long(n[0]) * n[1] * n[2] <= kCoarsestCells) break;
    // Pair the cells of each rank's block along every direction that can be coarsened (a block
    // of odd length ends in a single cell or a triple, pair_count; uniform pairs of an even whole where periodic, for the
    // red-black colouring), or, with level_pairs, the cells of the whole level where the coarser
    // level is not gathered. Where a block would fall below 2 cells on several ranks, the coarser
    // level is gathered along that direction: ranks 2c and 2c + 1 hand their aggregates to 2c.
    std::array<bool, 3> ok{}, merge{};
    bool any = false;
    for (int d = 0; d < 3; ++d) {
      ok[d] = n[d] >= 4 && (!periodic[d] || n[d] % 2 == 0);
      for (int c : own[d]) ok[d] = ok[d] && (!periodic[d] || c % 2 == 0);
      int first = 0;
      for (int c : own[d]) {
        merge[d] = merge[d] || (ok[d] && procs[d] > 1 && pair_count(c, first, plan.back().span[d]) < 2);
        first += c;
      }
      any = any || ok[d];
    }
    const bool gather = merge[0] || merge[1] || merge[2];
    for (int d = 0; d < 3; ++d) {
      fine_start[d].clear();
      crosses[d] = false;
      const auto& span = plan.back().span[d];
      if (level_pairs && ok[d] && !gather) {
        // Pairs over the whole level (cells 2I and 2I + 1; an odd whole ends as a block does), each
        // owned by the rank of its first cell: the aggregates one rank makes, whatever the cuts. A
        // pair across a cut makes its owner read its second cell's residual and coefficients, and
        // that cell's rank read the pair's correction, from the neighbour (theory F9a).
        const int total = n[d], count = pair_count(total, 0, span);
        for (int I = 0; I < count; ++I) fine_start[d].push_back(2 * I);
        fine_start[d].push_back(total);
        int first = 0;
        for (auto& c : own[d]) {
          int owned = 0;
          for (int I = 0; I < count; ++I) {
            const int f = fine_start[d][std::size_t(I)];
            owned += f >= first && f < first + c;
          }
          // A cut inside a pair (the block starts on its second cell).
          crosses[d] = crosses[d] || (first > 0 && !std::binary_search(fine_start[d].begin(), fine_start[d].end(), first));
          first += c;
          c = owned;
        }
      } else {
        int first = 0;
        for (auto& c : own[d]) {
          const int count = ok[d] ? pair_count(c, first, span) : c;
          for (int I = 0; I < count; ++I) fine_start[d].push_back(first + (ok[d] ? 2 * I : I));
          first += c;
          c = count;
        }
        fine_start[d].push_back(first);
      }
      n[d] = int(fine_start[d].size()) - 1;
    }
    if (!any) break;
    merged = merge;
    for (int d = 0; d < 3; ++d) parts[d] = gather ? own[d] : std::vector<int>{};
    for (int d = 0; d < 3; ++d)
      if (merge[d]) {
        std::vector<int> pairs;
        for (std::size_t b = 0; b < own[d].size(); b += 2) pairs.push_back(own[d][b] + (b + 1 < own[d].size() ? own[d][b + 1] : 0));
        own[d] = pairs;
      }
  }
  return plan;
}

double coarse_face_distance(const MultigridLevelPlan& fine, const MultigridLevelPlan& coarse, int d, int I,
                            bool periodic) {
  const int nc = coarse.n[d], nf = fine.n[d], i = coarse.fine_start[d][std::size_t(I)];
  const auto& W = coarse.span[d];
  const auto& w = fine.span[d];
  if (!periodic && I == 0) return double(W.front()) / w.front();
  if (!periodic && I == nc) return double(W.back()) / w.back();
  auto at = [](const std::vector<int>& v, int k, int n) { return v[std::size_t((k + n) % n)]; };
  return double(at(W, I - 1, nc) + at(W, I, nc)) / double(at(w, i - 1, nf) + at(w, i, nf));
}

int smoothing_exchanges(int sweeps, int layers, bool from_zero, bool ghosts_after) {
  // As CellMultigrid::smooth: an exchange before pass 0 unless from zero, then before the passes
  // that follow one (from zero 1, 1 + w, ...; else w, 2 w, ...), and one at the end where the first
  // ghost layer must hold the last pass and the last pass did not follow an exchange (two layers).
  const int passes = 2 * sweeps;
  if (passes == 0) return 0;
  const int first = from_zero ? 1 : 0;
  auto after_exchange = [&](int p) { return p >= first && (p - first) % layers == 0; };
  int count = from_zero ? 0 : 1;
  for (int p = 1; p < passes; ++p) count += after_exchange(p) ? 1 : 0;
  if (ghosts_after && !(layers == 2 && after_exchange(passes - 1))) ++count;
  return count;
}

std::vector<int> multigrid_exchanges(const std::vector<MultigridLevelPlan>& plan, int pre, int post, int coarse_sweeps,
                                     bool coarse_direct) {
  std::vector<int> count(plan.size(), 0);
  for (std::size_t l = 0; l < plan.size(); ++l) {
    const MultigridLevelPlan& L = plan[l];
    if (!L.halo) continue;
    if (l + 1 == plan.size())
      count[l] = coarse_direct ? 0
                               : smoothing_exchanges(coarse_sweeps / 2, L.layers, true, false) +
                                     smoothing_exchanges(coarse_sweeps / 2, L.layers, false, false);
    else
      count[l] = smoothing_exchanges(pre, L.layers, true, true) + smoothing_exchanges(post, L.layers, false, false);
    if (l == 0) count[l] += 1;  // the operator's (apply_operator), once a Krylov iteration
    // Aggregates across a cut: the finer level's residuals before the restriction, and this
    // level's correction before the prolongation.
    if (l > 0 && L.crossing()) count[l - 1] += 1, count[l] += 1;
  }
  return count;
}

}  // namespace tessera
