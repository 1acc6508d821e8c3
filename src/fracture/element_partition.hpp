// SPDX-License-Identifier: MIT
// Which rank owns each element of a bonded block (issue 19; docs/design.md "Parallel model"):
//   slabs     the process grid's equal slabs, by the element's initial centroid (the default)
//   balanced  the grid's cut planes at the weighted quantiles of the elements' work (core/balance.hpp)
//   metis     a METIS k-way partition of the element graph (elements joined by their bonds), the
//             vertices weighted by their updates and the edges by their bond's evaluations: a bond
//             whose elements are on two ranks is evaluated on both, so its cut is work as well.
//             With levels, one balance constraint per level f: the work of the sub-steps at which
//             the levels f and finer are due (each sub-step ends in an exchange that waits for every
//             rank, so each kind of sub-step is balanced, not only the macro step's sum). METIS also
//             partitions for the sum alone, and the partition whose macro step is shorter by
//             substep_time (below) is taken: with few elements per rank the constraints cannot all
//             be met (the seed's 958 on 16 ranks). The partition taken is then refined by single
//             moves of elements between bonded parts (refine_by_substeps).
// The work is what a macro step of B10 does: element e is updated 2^k_e times, a bond evaluated
// 2^max(k_i, k_j) times (one level for the uniform step). The owners change no result: an element
// is integrated by its owner, which sums its forces in bond, contact, hole order (fracture_solver.hpp).
#pragma once
#include <array>
#include <string>
#include <vector>

#include "core/vec3.hpp"
#include "fracture/bonded_block.hpp"

namespace tessera {

enum class Partition { slabs, balanced, metis };
Partition partition_from_name(const std::string& name);  // "slabs", "balanced", "metis"
const char* partition_name(Partition p);

// One evaluation of a bond costs this many element updates (measured 2026-11-30 on the fine block,
// 102,975 elements, stability levels, one rank: 230 ns per bond evaluation, 163 ns per update).
constexpr double kBondCostPerUpdate = 1.4;
// A listed contact pair's visit at a sub-step (its may-touch test, and its force where it may touch)
// costs this many element updates (2026-12-07, the fine block on 2 ranks: 128 s for 1.0e9 evaluations
// against 92 s for 0.88e9 updates a rank, with most visits a test only).
constexpr double kContactCostPerUpdate = 0.6;

struct ElementWork {
  std::vector<double> element;  // per element: updates per macro step
  std::vector<double> bond;     // per bond: evaluations per macro step times kBondCostPerUpdate (0: broken)
  std::vector<int> level;       // per element: the level it is updated at (its own or a pair's finer one)
  std::vector<int> bond_level;  // per bond: the finer of its two elements' levels
  // Listed contact pairs (a rebalance during a run): each sphere pair's two elements, visited at the
  // finer one's level at kContactCostPerUpdate, on both ranks when they differ.
  std::vector<std::array<int, 2>> contact;
  std::vector<int> contact_level;
};
// At the start: levels, every bond intact, no contact. During a run (a rebalance): the broken
// bonds (per bond, nonzero: broken) do no work and draw no level; `contacts` as ElementWork::contact.
ElementWork element_work(const BondedBlock& block, const std::vector<int>& level, const std::vector<char>& broken = {},
                         const std::vector<std::array<int, 2>>& contacts = {});

// Each element's part in [0, parts): for slabs and balanced the grid cell (x fastest) of
// dims = {nx, ny, nz} over the box [lo, hi]; for metis the METIS part (parts = nx ny nz).
std::vector<int> partition_elements(const BondedBlock& block, const ElementWork& work, Partition how, const Vec3& lo,
                                    const Vec3& hi, std::array<int, 3> dims);

// Moves elements linked to another part out of a sub-step kind's busiest part into a part they are
// linked to (a bond with work, or a listed pair), one at a time, the move that shortens the macro
// step's time most (substep_time of part_level_work), or, where none does, that leaves it and most
// lowers the sum over the kinds of the parts' squared work; until no move does either. No part is
// left empty. METIS's partitions are refined so (partition_elements): its constraints cannot all be
// met where a level holds a few elements a rank.
void refine_by_substeps(const BondedBlock& block, const ElementWork& work, std::vector<int>& part, int parts);

// Each part's work: its elements' updates and every bond with an element in it (a cut bond on both).
std::vector<double> part_work(const BondedBlock& block, const ElementWork& work, const std::vector<int>& part,
                              int parts);
long cut_bonds(const BondedBlock& block, const std::vector<int>& part);

// The levels of a work map (1 + the finest element level; 1 for the uniform step).
int work_levels(const ElementWork& work);
// Each part's work at a sub-step where the levels f and finer are due, per f = 0 .. levels - 1
// ([f][part]): its elements' updates at levels >= f and its bonds as fine as f (a cut bond on both).
// Each of these sub-steps ends in an exchange that waits for every rank, so each row's imbalance is
// a wait; row 0 (every element due) is the coarsest sub-step.
std::vector<std::vector<double>> part_level_work(const BondedBlock& block, const ElementWork& work,
                                                 const std::vector<int>& part, int parts);
// The stability levels' halo (build_halo) at the initial levels: per sub-step kind f and part, the
// element states it sends after that sub-step ([f][part]: its elements of level >= f bonded to
// another part's, once per such part), and per part the parts it exchanges with. The contacts' pairs
// across parts come later and are not counted.
struct LevelHalo {
  std::vector<std::vector<double>> sent;
  std::vector<int> neighbours;
};
LevelHalo part_level_halo(const BondedBlock& block, const ElementWork& work, const std::vector<int>& part, int parts);
// Each row's imbalance (max over mean).
std::vector<double> level_imbalance(const std::vector<std::vector<double>>& level_work);
// A macro step's time in units of work if each sub-step takes its busiest rank's work and ends in
// an exchange that waits for it: sum_f c_f max_f, where c_f sub-steps of a macro step have f as their
// coarsest due level (c_0 = 1, c_f = 2^(f-1): the sub-steps j of 2^(L-1) where f = L-1 - (the power
// of 2 in j)). substep_imbalance divides it by the same sum of the rows' means: the waits that a
// partition balancing only the macro step's sum leaves.
double substep_time(const std::vector<std::vector<double>>& level_work);
double substep_imbalance(const std::vector<std::vector<double>>& level_work);

}  // namespace tessera
