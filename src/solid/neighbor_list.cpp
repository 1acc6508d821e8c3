// SPDX-License-Identifier: MIT
#include "solid/neighbor_list.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

namespace tessera {

namespace {

// Sorts items by their pair key (two body keys below 2^32, usually far below): an LSD radix sort
// over the keys' significant bits, 11 at a time (3 passes for a million bodies), where std::sort
// made n log n comparisons. Keys are distinct, so the order is the one std::sort gives.
template <class Item>
void sort_by_pair_key(std::vector<Item>& items, std::vector<Item>& buffer) {
  const std::size_t n = items.size();
  if (n < 2) return;
  std::uint64_t max_lo = 0, max_hi = 0;
  for (const auto& it : items) max_lo = std::max<std::uint64_t>(max_lo, it.key >> 32), max_hi = std::max<std::uint64_t>(max_hi, it.key & 0xffffffffULL);
  const int bits_hi = std::bit_width(max_hi), bits = std::bit_width(max_lo) + bits_hi;
  auto packed = [bits_hi](std::uint64_t key) { return (key >> 32) << bits_hi | (key & 0xffffffffULL); };
  constexpr int kDigit = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigit;
  buffer.resize(n);
  std::vector<std::size_t> start(kBuckets);
  for (int shift = 0; shift < bits; shift += kDigit) {
    std::fill(start.begin(), start.end(), 0);
    for (const auto& it : items) ++start[(packed(it.key) >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (auto& c : start) sum += std::exchange(c, sum);
    for (const auto& it : items) buffer[start[(packed(it.key) >> shift) & (kBuckets - 1)]++] = it;
    items.swap(buffer);
  }
}

}  // namespace

ContactElements elements_of(const ParticleStore& p) {
  ContactElements e;
  e.size = p.size();
  e.owned = p.owned;
  e.x = p.x.data();
  e.radius = p.radius.data();
  e.key = p.order.data();
  e.body_mass = p.mass.data();
  return e;
}

void NeighborList::build(const ParticleStore& p, double skin, const HistoryMap& extra) { build(elements_of(p), skin, extra); }

int NeighborList::cell_coord(double x, int d) const {
  return std::clamp(static_cast<int>((x - lo_[d]) * inv_h_), 0, nc_[d] - 1);
}

void NeighborList::bin(const ContactElements& p, double skin) {
  const std::size_t n = p.size;
  double r_min = std::numeric_limits<double>::infinity(), r_max = 0;
  for (std::size_t i = 0; i < n; ++i) r_min = std::min(r_min, p.radius[i]), r_max = std::max(r_max, p.radius[i]);
  r_ref_ = std::min(r_max, 2.0 * r_min);
  // The small ghost elements far from the sub-box are left out (ContactElements::near; the large
  // ones, few, are always kept), and the grid spans the others only.
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  cell_of_.resize(n);
  left_out = 0;
  for (std::size_t i = 0; i < n; ++i) {
    cell_of_[i] = p.radius[i] > r_ref_ || p.near(i) ? 0 : kFar;
    if (cell_of_[i] == kFar) {
      ++left_out;
      continue;
    }
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p.x[p.stride * i + d]);
      hi[d] = std::max(hi[d], p.x[p.stride * i + d]);
    }
  }
  binned = n - left_out;
  if (binned == 0) lo = hi = Vec3{};
  double h = 2.0 * r_ref_ + skin;
  // Keep the grid at most ~4 cells per body (a body flung far away must not blow up memory).
  for (;;) {
    double cells = 1;
    for (int d = 0; d < 3; ++d) {
      nc_[d] = std::max(1, static_cast<int>((hi[d] - lo[d]) / h) + 1);
      cells *= nc_[d];
    }
    if (cells <= 4.0 * static_cast<double>(binned) + 64) break;
    h *= 1.5;
  }
  lo_ = lo;
  inv_h_ = 1.0 / h;
  const std::size_t ncell = static_cast<std::size_t>(nc_[0]) * nc_[1] * nc_[2];
  cell_start_.assign(ncell + 1, 0);
  cell_owned_end_.assign(ncell, 0);
  cell_items_.resize(n);
  large_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (cell_of_[i] == kFar) continue;
    if (p.radius[i] > r_ref_) {
      large_.push_back(static_cast<std::int32_t>(i));
      cell_of_[i] = -1;
      continue;
    }
    const int c = (cell_coord(p.x[p.stride * i + 2], 2) * nc_[1] + cell_coord(p.x[p.stride * i + 1], 1)) * nc_[0] +
                  cell_coord(p.x[p.stride * i], 0);
    cell_of_[i] = c;
    ++cell_start_[c + 1];
    cell_owned_end_[c] += i < p.owned;
  }
  for (std::size_t c = 0; c < ncell; ++c) cell_start_[c + 1] += cell_start_[c];
  // A cell's items in element order: its owned elements first (indices below p.owned), ending at
  // cell_owned_end_, then its ghosts.
  for (std::size_t c = 0; c < ncell; ++c) cell_owned_end_[c] += cell_start_[c];
  binned_owned_ = p.owned;
  std::vector<std::int32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    if (cell_of_[i] >= 0) cell_items_[fill[cell_of_[i]]++] = static_cast<std::int32_t>(i);
  moved_.assign(n, 0);
  moved_list_.clear();
}

inline void NeighborList::push_if_near(const ContactElements& p, std::int32_t a, std::int32_t b, const double* xa,
                                       const double* xb, double cut) {
  const double dx = xa[0] - xb[0], dy = xa[1] - xb[1], dz = xa[2] - xb[2];
  if (dx * dx + dy * dy + dz * dz >= cut * cut) return;
  const bool a_low = p.key[a] < p.key[b];
  candidates_.push_back({pair_key(p.key[a], p.key[b]), a_low ? a : b, a_low ? b : a});
}

inline void NeighborList::consider(const ContactElements& p, double skin, std::size_t a, std::size_t b, double extra) {
  if (a >= p.owned && b >= p.owned) return;
  if (p.body && p.body[a] == p.body[b]) return;
  push_if_near(p, static_cast<std::int32_t>(a), static_cast<std::int32_t>(b), p.x + p.stride * a, p.x + p.stride * b,
               p.radius[a] + p.radius[b] + skin + extra);
}

void NeighborList::build(const ContactElements& p, double skin, const HistoryMap& extra) {
  ++builds;
  list_all(p, skin, extra);
}

void NeighborList::list_all(const ContactElements& p, double skin, const HistoryMap& extra) {
  const std::size_t n = p.size;
  candidates_.clear();
  previous_keys_.swap(keys);
  previous_history_.swap(history);
  first.clear(), second.clear(), keys.clear(), history.clear(), meff.clear();
  if (n == 0) return;
  bin(p, skin);
  const int* nc = nc_;
  auto consider = [&](std::size_t a, std::size_t b) { this->consider(p, skin, a, b); };
  const std::int32_t* body = p.body;

  // The binned elements in cell order: most pairs the stencil meets are rejected (one body's
  // spheres share cells, or the two are too far apart), and reading their places in sequence costs
  // less than gathering them from the element arrays. A cell holds a body's elements in one run
  // (bin() fills it in element order, and a body's elements are consecutive): run_end_ skips it
  // whole (docs/performance.md, 2026-12-04, sixth session).
  const std::size_t binned = static_cast<std::size_t>(cell_start_.back());
  packed_.resize(binned);
  packed_body_.resize(binned);
  run_end_.resize(binned);
  for (std::size_t k = 0; k < binned; ++k) {
    const auto i = static_cast<std::size_t>(cell_items_[k]);
    packed_[k] = {p.x[p.stride * i], p.x[p.stride * i + 1], p.x[p.stride * i + 2], p.radius[i]};
    packed_body_[k] = body ? body[i] : static_cast<std::int32_t>(i);
  }
  const std::size_t ncell = cell_start_.size() - 1;
  for (std::size_t c = 0; c < ncell; ++c)
    for (int k = cell_start_[c + 1] - 1; k >= cell_start_[c]; --k)
      run_end_[k] = k + 1 < cell_start_[c + 1] && packed_body_[k + 1] == packed_body_[k] ? run_end_[k + 1] : k + 1;
  const auto owned = static_cast<std::int32_t>(p.owned);
  // consider()'s test on the packed copies (a = cell_items_[u]), for the elements [v, end) of one
  // cell that are not u's body's: a body's run skipped at once, the same reach test.
  auto consider_binned = [&](int u, int v, int end) {
    const std::int32_t a = cell_items_[u], body_u = packed_body_[u];
    const auto& xa = packed_[u];
    while (v < end) {
      ++tests;
      if (packed_body_[v] == body_u) {
        v = run_end_[v];
        continue;
      }
      const std::int32_t b = cell_items_[v];
      const auto& xb = packed_[v++];
      if (a >= owned && b >= owned) continue;
      push_if_near(p, a, b, xa.data(), xb.data(), xa[3] + xb[3] + skin);
    }
  };

  // Small-small: each pair once, from a half stencil over cells (the cell itself, then the 13
  // neighbours ahead of it in (z, y, x) order).
  static constexpr int kHalf[13][3] = {{1, 0, 0},  {-1, 1, 0}, {0, 1, 0},  {1, 1, 0}, {-1, -1, 1},
                                       {0, -1, 1}, {1, -1, 1}, {-1, 0, 1}, {0, 0, 1}, {1, 0, 1},
                                       {-1, 1, 1}, {0, 1, 1},  {1, 1, 1}};
  for (int cz = 0; cz < nc[2]; ++cz)
    for (int cy = 0; cy < nc[1]; ++cy)
      for (int cx = 0; cx < nc[0]; ++cx) {
        const int c = (cz * nc[1] + cy) * nc[0] + cx;
        const int begin = cell_start_[c], end = cell_start_[c + 1], owned_end = cell_owned_end_[c];
        if (begin == end) continue;
        // A ghost's partners are owned (theory T5c): it scans the owned prefix of each cell only,
        // and none of its own cell's later items (ghosts too).
        for (int u = begin; u < owned_end; ++u) consider_binned(u, run_end_[u], end);
        for (const auto& o : kHalf) {
          const int x = cx + o[0], y = cy + o[1], z = cz + o[2];
          if (x < 0 || y < 0 || z < 0 || x >= nc[0] || y >= nc[1] || z >= nc[2]) continue;
          const int cc = (z * nc[1] + y) * nc[0] + x;
          for (int u = begin; u < owned_end; ++u) consider_binned(u, cell_start_[cc], cell_start_[cc + 1]);
          for (int u = owned_end; u < end; ++u) consider_binned(u, cell_start_[cc], cell_owned_end_[cc]);
        }
      }
  // Large-small: each large body scans the cells within its reach.
  for (const auto li : large_) {
    const double reach = p.radius[li] + r_ref_ + skin;
    int c0[3], c1[3];
    for (int d = 0; d < 3; ++d) {
      c0[d] = cell_coord(p.x[p.stride * li + d] - reach, d);
      c1[d] = cell_coord(p.x[p.stride * li + d] + reach, d);
    }
    const bool ghost = static_cast<std::size_t>(li) >= p.owned;
    for (int z = c0[2]; z <= c1[2]; ++z)
      for (int y = c0[1]; y <= c1[1]; ++y)
        for (int x = c0[0]; x <= c1[0]; ++x) {
          const int cc = (z * nc[1] + y) * nc[0] + x;
          const int stop = ghost ? cell_owned_end_[cc] : cell_start_[cc + 1];
          tests += static_cast<std::size_t>(stop - cell_start_[cc]);
          for (int k = cell_start_[cc]; k < stop; ++k) consider(li, cell_items_[k]);
        }
  }
  // Large-large: few of them, all pairs.
  for (std::size_t a = 0; a < large_.size(); ++a)
    for (std::size_t b = a + 1; b < large_.size(); ++b) consider(large_[a], large_[b]);

  sort_by_pair_key(candidates_, sorted_);
  const std::size_t np = candidates_.size();
  first.resize(np), second.resize(np), keys.resize(np), history.assign(3 * np, 0.0), meff.resize(np);
  std::size_t old = 0;
  const std::size_t n_old = previous_keys_.size();
  for (std::size_t k = 0; k < np; ++k) {
    first[k] = candidates_[k].a;
    second[k] = candidates_[k].b;
    keys[k] = candidates_[k].key;
    const std::size_t ba = body ? static_cast<std::size_t>(body[first[k]]) : static_cast<std::size_t>(first[k]);
    const std::size_t bb = body ? static_cast<std::size_t>(body[second[k]]) : static_cast<std::size_t>(second[k]);
    const double ma = p.body_mass[ba], mb = p.body_mass[bb];
    meff[k] = ma * mb / (ma + mb);
    while (old < n_old && previous_keys_[old] < keys[k]) ++old;
    if (old < n_old && previous_keys_[old] == keys[k]) {
      for (int d = 0; d < 3; ++d) history[3 * k + d] = previous_history_[3 * old + d];
    } else if (!extra.empty()) {
      const auto it = extra.find(keys[k]);
      if (it != extra.end())
        for (int d = 0; d < 3; ++d) history[3 * k + d] = it->second[d];
    }
  }
}

bool NeighborList::relist(const ContactElements& p, double skin, const std::vector<char>& stale,
                          const std::vector<double>& travel) {
  ++relists;
  const std::size_t n = p.size;
  if (n == 0) return false;
  // Per element: stale or not, and how far a fresh element's body has gone since its own listing.
  stale_el_.resize(n);
  std::size_t stale_elements = 0;
  double fresh_travel = 0;
  for (std::size_t a = 0; a < n; ++a) {
    const std::size_t body = p.body ? static_cast<std::size_t>(p.body[a]) : a;
    stale_el_[a] = stale[body];
    stale_elements += stale_el_[a] != 0;
    if (!stale_el_[a]) fresh_travel = std::max(fresh_travel, travel[body]);
  }
  // Most elements stale (a bed's grains falling together): each of them would search a wider
  // reach from both sides of every pair; one half-stencil pass over all of them costs less.
  // (A quarter: a falling bed's relist to 0.04 s took the same time with an eighth and 1.3 times as
  // long with a half; docs/performance.md, 2026-12-04.)
  if (4 * stale_elements > n) {
    list_all(p, skin, {});
    return true;
  }
  auto travel_of = [&](std::size_t b) { return travel[p.body ? static_cast<std::size_t>(p.body[b]) : b]; };
  // The elements listed again since the last bin lie in moved_cells_ at their current place; the
  // others in the cells, within skin/2 of where they were binned (none of them is stale). When the
  // moved ones are many, all are binned again.
  if (moved_.size() != n || binned_owned_ != p.owned || 8 * (moved_list_.size() + stale_elements) > n) bin(p, skin);
  // A stale element left out at the bin joins the moved ones once it is near the sub-box; until then
  // no owned element can reach it, and it searches nothing (theory T5b).
  auto searched = [&](std::size_t a) { return cell_of_[a] != kFar || moved_[a] || p.near(a); };
  for (std::size_t a = 0; a < n; ++a)
    if (stale_el_[a] && !moved_[a] && cell_of_[a] != -1 && searched(a))
      moved_[a] = 1, moved_list_.push_back(static_cast<std::int32_t>(a));
  auto cell_of = [&](const double* x) {
    return (cell_coord(x[2], 2) * nc_[1] + cell_coord(x[1], 1)) * nc_[0] + cell_coord(x[0], 0);
  };
  moved_cells_.clear();
  for (const auto e : moved_list_) moved_cells_.emplace_back(cell_of(&p.x[p.stride * static_cast<std::size_t>(e)]), e);
  std::sort(moved_cells_.begin(), moved_cells_.end());
  candidates_.clear();
  // From each element of a stale body, every element within reach: R_a + R_b + skin, plus, for an
  // element not listed again now, how far its body has gone since its own listing (it may come back
  // that far towards a; theory T5a). A pair of two stale elements from the one with the lower key
  // (both searches cover each other: the reaches are symmetric).
  auto from = [&](std::size_t a, std::size_t b) {
    if (a == b) return;
    if (stale_el_[b]) {
      if (p.key[b] < p.key[a]) return;
      consider(p, skin, a, b, 0.0);
    } else {
      consider(p, skin, a, b, travel_of(b));
    }
  };
  for (std::size_t a = 0; a < n; ++a) {
    if (!stale_el_[a] || !searched(a)) continue;
    const bool ghost = a >= p.owned;  // its partners are owned: the cells' owned prefixes (T5c)
    const double* xa = &p.x[p.stride * a];
    const double reach = p.radius[a] + r_ref_ + skin + fresh_travel, binned_reach = reach + 0.5 * skin;
    int c0[3], c1[3], m0[3], m1[3];
    for (int d = 0; d < 3; ++d) {
      c0[d] = cell_coord(xa[d] - binned_reach, d), c1[d] = cell_coord(xa[d] + binned_reach, d);
      m0[d] = cell_coord(xa[d] - reach, d), m1[d] = cell_coord(xa[d] + reach, d);
    }
    for (int z = c0[2]; z <= c1[2]; ++z)
      for (int y = c0[1]; y <= c1[1]; ++y)
        for (int x = c0[0]; x <= c1[0]; ++x) {
          const int cc = (z * nc_[1] + y) * nc_[0] + x;
          const int stop = ghost ? cell_owned_end_[cc] : cell_start_[cc + 1];
          tests += static_cast<std::size_t>(stop - cell_start_[cc]);
          for (int k = cell_start_[cc]; k < stop; ++k) {
            const auto b = static_cast<std::size_t>(cell_items_[k]);
            if (!moved_[b]) from(a, b);
          }
        }
    for (int z = m0[2]; z <= m1[2]; ++z)
      for (int y = m0[1]; y <= m1[1]; ++y) {
        const int row = (z * nc_[1] + y) * nc_[0];
        auto it = std::lower_bound(moved_cells_.begin(), moved_cells_.end(), std::pair<std::int32_t, std::int32_t>{row + m0[0], -1});
        for (; it != moved_cells_.end() && it->first <= row + m1[0]; ++it) {
          const auto b = static_cast<std::size_t>(it->second);
          ++tests;
          if (!ghost || b < p.owned) from(a, b);
        }
      }
    for (const auto l : large_) from(a, static_cast<std::size_t>(l));  // always at their current place
  }
  sort_by_pair_key(candidates_, sorted_);
  merge_relisted(p);
  return false;
}

// The kept pairs (no stale element) and the new ones, both sorted by key, into one sorted list; a
// new pair that was listed before takes its history. Runs of kept pairs are copied whole.
void NeighborList::merge_relisted(const ContactElements& p) {
  const std::size_t n_old = keys.size(), n_new = candidates_.size(), cap = n_old + n_new;
  if (merged_keys_.size() < cap) {
    merged_first_.resize(cap), merged_second_.resize(cap), merged_keys_.resize(cap);
    merged_history_.resize(3 * cap), merged_meff_.resize(cap);
  }
  auto old_stale = [&](std::size_t o) { return stale_el_[static_cast<std::size_t>(first[o])] | stale_el_[static_cast<std::size_t>(second[o])]; };
  auto body_mass = [&](std::int32_t e) { return p.body_mass[p.body ? static_cast<std::size_t>(p.body[e]) : static_cast<std::size_t>(e)]; };
  std::size_t o = 0, c = 0, w = 0;
  while (o < n_old || c < n_new) {
    const PairKey next_new = c < n_new ? candidates_[c].key : std::numeric_limits<PairKey>::max();
    std::size_t run = o;
    while (run < n_old && keys[run] < next_new && !old_stale(run)) ++run;
    if (run > o) {
      const std::size_t len = run - o;
      std::copy_n(&first[o], len, &merged_first_[w]), std::copy_n(&second[o], len, &merged_second_[w]);
      std::copy_n(&keys[o], len, &merged_keys_[w]), std::copy_n(&meff[o], len, &merged_meff_[w]);
      std::copy_n(&history[3 * o], 3 * len, &merged_history_[3 * w]);
      w += len, o = run;
    }
    if (o < n_old && keys[o] < next_new) {
      ++o;  // a stale element's pair, no longer within reach
      continue;
    }
    if (c == n_new) break;
    const Candidate& k = candidates_[c++];
    double* h = &merged_history_[3 * w];
    if (o < n_old && keys[o] == k.key) {  // listed before (stale: found again)
      std::copy_n(&history[3 * o], 3, h);
      ++o;
    } else {
      h[0] = h[1] = h[2] = 0.0;
    }
    const double ma = body_mass(k.a), mb = body_mass(k.b);
    merged_first_[w] = k.a, merged_second_[w] = k.b, merged_keys_[w] = k.key, merged_meff_[w] = ma * mb / (ma + mb);
    ++w;
  }
  first.swap(merged_first_), second.swap(merged_second_), keys.swap(merged_keys_);
  history.swap(merged_history_), meff.swap(merged_meff_);
  first.resize(w), second.resize(w), keys.resize(w), history.resize(3 * w), meff.resize(w);
}

void NeighborList::collect(HistoryMap& out) const {
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const double* h = &history[3 * k];
    if (h[0] != 0.0 || h[1] != 0.0 || h[2] != 0.0) out[keys[k]] = {h[0], h[1], h[2]};
  }
}

}  // namespace tessera
