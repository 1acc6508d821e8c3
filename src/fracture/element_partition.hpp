// SPDX-License-Identifier: MIT
// Which rank owns each element of a bonded block (issue 19; docs/design.md "Parallel model"):
//   slabs     the process grid's equal slabs, by the element's initial centroid (the default)
//   balanced  the grid's cut planes at the weighted quantiles of the elements' work (core/balance.hpp)
//   metis     a METIS k-way partition of the element graph (elements joined by their bonds), the
//             vertices weighted by their updates and the edges by their bond's evaluations: a bond
//             whose elements are on two ranks is evaluated on both, so its cut is work as well.
//             With levels, one balance constraint per level f: the work of the sub-steps at which
//             the levels f and finer are due (each sub-step ends in an exchange that waits for every
//             rank, so each kind of sub-step is balanced, not only the macro step's sum), unless
//             that leaves the sum more than 5 % above the mean (too few elements per rank): then
//             the sum alone.
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

struct ElementWork {
  std::vector<double> element;  // per element: updates per macro step
  std::vector<double> bond;     // per bond: evaluations per macro step times kBondCostPerUpdate
  std::vector<int> level;       // per element: the level it is updated at (its own or a bond's finer one)
  std::vector<int> bond_level;  // per bond: the finer of its two elements' levels
};
ElementWork element_work(const BondedBlock& block, const std::vector<int>& level);

// Each element's part in [0, parts): for slabs and balanced the grid cell (x fastest) of
// dims = {nx, ny, nz} over the box [lo, hi]; for metis the METIS part (parts = nx ny nz).
std::vector<int> partition_elements(const BondedBlock& block, const ElementWork& work, Partition how, const Vec3& lo,
                                    const Vec3& hi, std::array<int, 3> dims);

// Each part's work: its elements' updates and every bond with an element in it (a cut bond on both).
std::vector<double> part_work(const BondedBlock& block, const ElementWork& work, const std::vector<int>& part,
                              int parts);
long cut_bonds(const BondedBlock& block, const std::vector<int>& part);

}  // namespace tessera
