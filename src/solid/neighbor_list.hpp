// SPDX-License-Identifier: MIT
// Contact detection: linked cells + a Verlet list with a skin. Pairs closer than
// R_a + R_b + skin are listed; the list stays valid until some body has moved more than skin/2
// since the build (checked every step, globally, so the rebuild step does not depend on the rank
// count).
//
// Size ratios: the cell size follows the small bodies (2 r_ref + skin, r_ref = min(r_max, 2 r_min));
// a body larger than r_ref scans the cells its reach covers, so one 43 mm ball among 0.6 mm grains
// costs one scan of its neighbourhood, not a grid of 45 mm cells.
//
// Determinism: pairs are stored in canonical orientation (lower order key first, see
// ParticleStore::order) and sorted by (lower key, higher key). Forces accumulated in that order reach
// each body in the order of its partners' keys, whatever the decomposition: results are bitwise
// independent of the rank count (tests/mpi/test_rank_independence.cpp).
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "solid/contact_history.hpp"
#include "solid/particles.hpp"

namespace tessera {

// What the list is built over: contact elements. For plain spheres an element is a body; for bodies
// made of contact spheres (shape templates) each sphere is an element, pairs within one body are
// never listed, and keys are element keys (body order * stride + sphere index).
struct ContactElements {
  std::size_t size = 0, owned = 0;  // elements of owned bodies first
  const double* x = nullptr;        // element i at x[stride * i], 3 coordinates
  std::size_t stride = 3;
  const double* radius = nullptr;
  const std::int64_t* key = nullptr;   // canonical, unique
  const std::int32_t* body = nullptr;  // local body per element; nullptr: element i is body i
  const double* body_mass = nullptr;
  // Ghost elements (index >= owned) whose place lies outside [near_lo, near_hi] are not listed: no
  // owned element can come within reach of them before the next whole build (DemSolver sets the
  // box, theory T5b). The default box holds everything.
  Vec3 near_lo{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, near_hi{HUGE_VAL, HUGE_VAL, HUGE_VAL};
  bool near(std::size_t i) const {
    if (i < owned) return true;
    for (int d = 0; d < 3; ++d)
      if (!(x[stride * i + d] >= near_lo[d] && x[stride * i + d] <= near_hi[d])) return false;
    return true;
  }
};

// A store's bodies as elements (each body one element).
ContactElements elements_of(const ParticleStore& p);

class NeighborList {
 public:
  void build(const ContactElements& e, double skin, const HistoryMap& extra);
  // Lists pairs with at least one owned body. A pair's history comes from the previous list (a
  // merge of the two sorted key lists), else from `extra` (bodies that migrated in, a restart),
  // else starts at zero.
  void build(const ParticleStore& p, double skin, const HistoryMap& extra);
  // Touching pairs' histories (non-zero), for the next build or for migration.
  void collect(HistoryMap& out) const;
  // Lists again the pairs of the elements whose body is stale (stale[body] != 0; e.body, or element
  // i is body i): their pairs leave the list and every pair within R_a + R_b + skin of them now is
  // found from a grid of all elements at their current positions, the reach grown, for a partner
  // not listed again, by travel[its body] (how far it has gone since its own listing, at most
  // skin/2); the other pairs stay, with their histories, and the list stays sorted. Valid while
  // every body has moved less than skin/2 since its own last listing (theory T5a). When most
  // elements are stale it lists every pair afresh instead, as build() does (histories by key), and
  // returns true: every body is then listed at its current place.
  bool relist(const ContactElements& e, double skin, const std::vector<char>& stale, const std::vector<double>& travel);

  std::size_t size() const { return first.size(); }
  std::vector<std::int32_t> first, second;  // local element indices; key[first] < key[second]
  std::vector<PairKey> keys;
  std::vector<double> history;  // 3 per pair (xi of eq. 5)
  std::vector<double> meff;     // m_a m_b / (m_a + m_b), constant while listed

  std::size_t builds = 0, relists = 0;
  // Work counter: the elements the searches met (each a place read, most rejected at once), over
  // every build and relist; a ghost meets the owned elements only (theory T5c).
  std::size_t tests = 0;
  // Elements the last bin() left out (ghosts outside the near box), and those it binned.
  std::size_t left_out = 0, binned = 0;

 private:
  struct Candidate {
    PairKey key;
    std::int32_t a, b;
  };
  std::vector<Candidate> candidates_, sorted_;  // sorted_: the radix sort's other buffer
  std::vector<PairKey> previous_keys_;
  std::vector<double> previous_history_;
  std::vector<std::int32_t> cell_start_, cell_items_, cell_of_, large_;  // cell_of_: -1 large, kFar left out
  std::vector<std::int32_t> cell_owned_end_;  // per cell: where its owned items end (they come first)
  std::size_t binned_owned_ = 0;             // p.owned at the last bin()
  static constexpr std::int32_t kFar = -2;
  // list_all(): the binned elements' places and radii (x, y, z, r) and bodies in cell_items_'
  // order, so that the half stencil reads them in sequence rather than scattered over the arrays.
  std::vector<std::array<double, 4>> packed_;
  std::vector<std::int32_t> packed_body_, run_end_;
  // The grid of the last bin(): cells of width 1 / inv_h_ from lo_, nc_ per direction; elements
  // larger than r_ref_ are in large_, not in the cells.
  int nc_[3] = {1, 1, 1};
  Vec3 lo_;
  double inv_h_ = 0, r_ref_ = 0;
  void bin(const ContactElements& e, double skin);
  int cell_coord(double x, int d) const;
  // Appends (a, b) to candidates_ when it may be listed: not two ghosts, not one body, within reach.
  void consider(const ContactElements& e, double skin, std::size_t a, std::size_t b, double extra = 0.0);
  // The reach test both searches share (consider(), and the whole listing's on cell-ordered copies):
  // places xa, xb closer than cut, then the pair in key order.
  void push_if_near(const ContactElements& e, std::int32_t a, std::int32_t b, const double* xa, const double* xb,
                    double cut);
  void merge_relisted(const ContactElements& e);
  void list_all(const ContactElements& e, double skin, const HistoryMap& extra);  // build() less its count
  // Elements listed again since the last bin() (relist): they are not looked up in the cells, where
  // they lie where they were, but in moved_cells_ (cell, element), sorted, at their current place.
  std::vector<char> moved_;
  std::vector<std::int32_t> moved_list_;
  std::vector<std::pair<std::int32_t, std::int32_t>> moved_cells_;
  std::vector<char> stale_el_;  // relist(): per element, its body's stale flag
  // relist()'s merge buffers
  std::vector<std::int32_t> merged_first_, merged_second_;
  std::vector<PairKey> merged_keys_;
  std::vector<double> merged_history_, merged_meff_;
};

}  // namespace tessera
