// SPDX-License-Identifier: MIT
// The contact list equals brute force: every pair within R_a + R_b + skin with at least one owned
// body, once, in canonical order (lower order key first, sorted), including bodies far larger than the
// cell size (the bunker's 43 mm ball among 0.6 mm grains) and polydisperse grains.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "solid/neighbor_list.hpp"

namespace tessera {
namespace {

ParticleStore make_bodies(std::size_t owned, std::size_t ghosts, double big_radius) {
  ParticleStore p;
  std::uint64_t z = 12345;
  auto rnd = [&z] {
    z = z * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  };
  const double L = 0.02;
  for (std::size_t i = 0; i < owned + ghosts; ++i) {
    const double r = 3e-4 * (0.8 + 0.6 * rnd());
    p.push_back(static_cast<std::int64_t>((i * 7919) % 100003), 0, r, 1.0, 1.0, {L * rnd(), L * rnd(), L * rnd()}, {},
                {});
  }
  if (big_radius > 0) p.push_back(100500, 0, big_radius, 1.0, 1.0, {0.5 * L, 0.5 * L, 0.5 * L}, {}, {});
  // The big body and the first `owned` bodies are owned: move the big one to the owned block.
  const std::size_t big = p.size() - 1;
  if (big_radius > 0) p.swap(owned, big);
  p.owned = owned + (big_radius > 0 ? 1 : 0);
  p.ghosts = p.size() - p.owned;
  for (std::size_t i = 0; i < p.size(); ++i) p.order[i] = p.id[i];  // any permanent unique key
  return p;
}

void expect_brute_force(const ParticleStore& p, double skin) {
  std::set<PairKey> expected;
  for (std::size_t a = 0; a < p.size(); ++a)
    for (std::size_t b = a + 1; b < p.size(); ++b) {
      if (a >= p.owned && b >= p.owned) continue;
      const double cut = p.radius[a] + p.radius[b] + skin;
      if (norm2(p.pos(a) - p.pos(b)) < cut * cut) expected.insert(pair_key(p.order[a], p.order[b]));
    }
  NeighborList list;
  list.build(p, skin, {});
  std::set<PairKey> got(list.keys.begin(), list.keys.end());
  EXPECT_EQ(got.size(), list.size()) << "a pair is listed twice";
  EXPECT_EQ(got, expected);
  EXPECT_TRUE(std::is_sorted(list.keys.begin(), list.keys.end()));
  for (std::size_t k = 0; k < list.size(); ++k) EXPECT_LT(p.order[list.first[k]], p.order[list.second[k]]);
}

TEST(NeighborList, EqualsBruteForcePolydisperse) { expect_brute_force(make_bodies(1500, 500, 0), 1.5e-4); }

TEST(NeighborList, EqualsBruteForceWithALargeBody) {
  const ParticleStore p = make_bodies(1500, 500, 21.5e-3 * 0.4);  // ratio ~30 to the grains
  expect_brute_force(p, 1.5e-4);
}

TEST(NeighborList, CarriesHistoriesOfListedPairs) {
  ParticleStore p;
  p.push_back(1, 0, 1e-3, 1, 1, {0, 0, 0}, {}, {});
  p.push_back(2, 0, 1e-3, 1, 1, {1.9e-3, 0, 0}, {}, {});
  p.push_back(3, 0, 1e-3, 1, 1, {9e-3, 0, 0}, {}, {});
  p.owned = 3;
  p.order = {1, 2, 3};
  HistoryMap h{{pair_key(1, 2), {1e-6, 2e-6, 0}}, {pair_key(2, 3), {5.0, 5.0, 5.0}}};
  NeighborList list;
  list.build(p, 1e-4, h);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list.history[0], 1e-6);
  EXPECT_EQ(list.history[1], 2e-6);
  HistoryMap back;
  list.collect(back);
  EXPECT_EQ(back.size(), 1u);  // (2, 3) is not listed: it cannot touch, its history is gone
}

}  // namespace
}  // namespace tessera
