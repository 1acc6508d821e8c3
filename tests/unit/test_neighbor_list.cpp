// SPDX-License-Identifier: MIT
// The contact list equals brute force: every pair within R_a + R_b + skin with at least one owned
// body, once, in canonical order (lower order key first, sorted), including bodies far larger than the
// cell size (the bunker's 43 mm ball among 0.6 mm grains) and polydisperse grains.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>
#include <vector>

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

// Relisting (theory T5a) keeps every pair that touches listed, whatever the order of the bodies'
// listings: each body is listed again alone when it has gone skin/2 from where it was last listed.
struct Relister {
  ParticleStore& p;
  double skin;
  NeighborList list;
  std::vector<double> listed_at;  // each body's place at its last listing
  void build() {
    list.build(p, skin, {});
    listed_at = p.x;
  }
  void step() {  // after the bodies moved: relist the stale ones
    std::vector<char> stale(p.size(), 0);
    std::vector<double> travel(p.size(), 0.0);
    bool any = false;
    for (std::size_t i = 0; i < p.size(); ++i) {
      travel[i] = std::sqrt(norm2(p.pos(i) - Vec3::load(&listed_at[3 * i])));
      if (travel[i] > 0.5 * skin) stale[i] = 1, any = true;
    }
    if (!any) return;
    if (list.relist(elements_of(p), skin, stale, travel)) stale.assign(p.size(), 1);  // all listed anew
    for (std::size_t i = 0; i < p.size(); ++i)
      if (stale[i]) std::copy_n(&p.x[3 * i], 3, &listed_at[3 * i]);
  }
  // Listed, once, in canonical order: every pair with an owned body closer than R_a + R_b + skin
  // less the two bodies' travels since their own listings (so every touching pair, until one of the
  // two is stale). A pair left out was at least R_a + R_b + skin + (the other's travel then) apart
  // at the later of the two listings (theory T5a).
  void expect_complete(const std::string& when) const {
    std::set<PairKey> listed(list.keys.begin(), list.keys.end());
    ASSERT_EQ(listed.size(), list.size()) << when << ": a pair listed twice";
    ASSERT_TRUE(std::is_sorted(list.keys.begin(), list.keys.end())) << when;
    std::vector<double> travel(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) travel[i] = std::sqrt(norm2(p.pos(i) - Vec3::load(&listed_at[3 * i])));
    for (std::size_t a = 0; a < p.size(); ++a)
      for (std::size_t b = a + 1; b < p.size(); ++b) {
        if (a >= p.owned && b >= p.owned) continue;
        const double touch = p.radius[a] + p.radius[b] + skin - travel[a] - travel[b];
        if (norm2(p.pos(a) - p.pos(b)) < touch * touch) {
          ASSERT_TRUE(listed.count(pair_key(p.order[a], p.order[b]))) << when << ": bodies " << a << ", " << b << " within reach, not listed";
        }
      }
  }
};

// The case the partner's own travel is for: b moves skin/2 away before a is listed again at just
// over R_a + R_b + skin from it, then both come back (a by less than skin/2 since its listing, b by
// less than skin/2 from its own listing place: skin in all since a's listing). They overlap, and the
// pair must have been listed at a's relisting.
TEST(NeighborList, RelistReachesAPartnerThatMayComeBack) {
  const double r = 1.0, s = 0.2;
  ParticleStore p;
  p.push_back(1, 0, r, 1, 1, {0, 0, 0}, {}, {});
  p.push_back(2, 0, r, 1, 1, {2.3, 0, 0}, {}, {});
  // Eight bodies at rest far away, so that one stale body of ten is relisted alone (a quarter of
  // them stale would make the relist a whole list).
  for (int k = 0; k < 8; ++k) p.push_back(3 + k, 0, r, 1, 1, {0, 100.0 + 3.0 * k, 0}, {}, {});
  p.owned = p.size();
  for (std::size_t i = 0; i < p.size(); ++i) p.order[i] = p.id[i];
  Relister rl{p, s, {}, {}};
  rl.build();
  EXPECT_EQ(rl.list.size(), 0u);  // 2.3 apart: beyond 2 r + s
  p.x[3] = 2.399;                  // b goes away, 0.099 < s/2: not stale
  rl.step();
  p.x[0] = 0.15;  // a goes 0.15 > s/2 towards b: stale, listed again 2.249 from b (> 2 r + s)
  rl.step();
  EXPECT_EQ(rl.list.relists, 1u);
  p.x[0] = 0.249, p.x[3] = 2.201;  // both back, each 0.099 from its own listing place: 1.952 apart
  rl.step();
  EXPECT_EQ(rl.list.relists, 1u);
  rl.expect_complete("after both came back");
}

// Many grains (owned and ghosts, one large body) jiggling at random, each listed again alone when
// stale: at every step every touching pair is listed, and a listed pair keeps its history.
TEST(NeighborList, RelistedListStaysCompleteUnderRandomMotion) {
  ParticleStore p = make_bodies(400, 100, 3e-3);
  const double skin = 1.5e-4;
  std::uint64_t z = 777;
  auto rnd = [&z] {
    z = z * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(z >> 11) * 0x1.0p-53 - 0.5;
  };
  // Packed closer: shrink the cloud towards its centre so that many pairs touch.
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int d = 0; d < 3; ++d) p.x[3 * i + d] = 0.01 + 0.45 * (p.x[3 * i + d] - 0.01);
  Relister rl{p, skin, {}, {}};
  rl.build();
  for (std::size_t k = 0; k < rl.list.size(); ++k) rl.list.history[3 * k] = static_cast<double>(rl.list.keys[k] % 1000);
  std::size_t relists = 0;
  for (int step = 0; step < 200; ++step) {
    // Each body drifts with its own velocity that turns now and then, so bodies go out and come back.
    for (std::size_t i = 0; i < p.size(); ++i)
      for (int d = 0; d < 3; ++d) p.x[3 * i + d] += 0.03 * skin * std::sin(0.05 * step * (1 + i % 7) + d + i) + 0.02 * skin * rnd();
    rl.step();
    relists = rl.list.relists;
    rl.expect_complete("step " + std::to_string(step));
    for (std::size_t k = 0; k < rl.list.size(); ++k)
      if (rl.list.history[3 * k] != 0.0) {
        ASSERT_EQ(rl.list.history[3 * k], static_cast<double>(rl.list.keys[k] % 1000));
      }
  }
  EXPECT_GT(relists, 50u);
}

// Grains falling together (a bed's deposition): when most bodies are stale the relist lists every
// pair afresh, as a build at the same places would, keeping the springs of the pairs that stay; when
// few are, only theirs.
TEST(NeighborList, MostlyStaleRelistIsAWholeListWithTheSprings) {
  ParticleStore p = make_bodies(400, 100, 0);
  const double skin = 1.5e-4;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int d = 0; d < 3; ++d) p.x[3 * i + d] = 0.01 + 0.45 * (p.x[3 * i + d] - 0.01);
  Relister rl{p, skin, {}, {}};
  rl.build();
  for (std::size_t k = 0; k < rl.list.size(); ++k) rl.list.history[3 * k] = static_cast<double>(rl.list.keys[k] % 1000 + 1);
  const std::size_t listed = rl.list.size();
  // All but five bodies fall by 0.6 skin; the five stay and so come 0.6 skin closer to those above.
  for (std::size_t i = 5; i < p.size(); ++i) p.x[3 * i + 2] -= 0.6 * skin;
  std::vector<char> stale(p.size(), 1);
  std::vector<double> travel(p.size(), 0.6 * skin);
  for (std::size_t i = 0; i < 5; ++i) stale[i] = 0, travel[i] = 0.0;
  const std::vector<PairKey> before = rl.list.keys;
  const std::vector<double> springs = rl.list.history;
  EXPECT_TRUE(rl.list.relist(elements_of(p), skin, stale, travel));
  std::set<PairKey> expected;  // brute force: every pair within R_a + R_b + skin now
  for (std::size_t a = 0; a < p.size(); ++a)
    for (std::size_t b = a + 1; b < p.size(); ++b) {
      const double cut = p.radius[a] + p.radius[b] + skin;
      if ((a < p.owned || b < p.owned) && norm2(p.pos(a) - p.pos(b)) < cut * cut) expected.insert(pair_key(p.order[a], p.order[b]));
    }
  EXPECT_EQ(std::set<PairKey>(rl.list.keys.begin(), rl.list.keys.end()), expected);
  NeighborList fresh;
  fresh.build(p, skin, {});
  EXPECT_EQ(rl.list.keys, fresh.keys);
  EXPECT_EQ(rl.list.first, fresh.first);
  EXPECT_EQ(rl.list.second, fresh.second);
  std::size_t kept = 0;
  for (std::size_t k = 0; k < rl.list.size(); ++k) {
    const auto it = std::lower_bound(before.begin(), before.end(), rl.list.keys[k]);
    const bool was = it != before.end() && *it == rl.list.keys[k];
    EXPECT_EQ(rl.list.history[3 * k], was ? springs[3 * static_cast<std::size_t>(it - before.begin())] : 0.0);
    kept += was;
  }
  EXPECT_GT(kept, listed / 2);
  EXPECT_EQ(rl.list.relists, 1u);
  EXPECT_EQ(rl.list.builds, 1u);  // the first build only: a relist is counted as one
  // Five stale bodies of 500: listed again alone.
  rl.listed_at = p.x;
  for (std::size_t i = 0; i < 5; ++i) p.x[3 * i] += 0.6 * skin;
  std::vector<char> few(p.size(), 0);
  for (std::size_t i = 0; i < 5; ++i) few[i] = 1;
  EXPECT_FALSE(rl.list.relist(elements_of(p), skin, few, std::vector<double>(p.size(), 0.0)));
}

// Bodies of 12 elements each (radius 0.2 mm, within 0.4 mm of the body's centre along each axis),
// the first `owned` of them owned; centre(i, rnd) places body i.
struct ElementBodies {
  static constexpr std::size_t per_body = 12;
  static constexpr double r = 2e-4;
  std::uint64_t z;
  std::vector<double> x, radius, mass;
  std::vector<std::int64_t> key;
  std::vector<std::int32_t> body;
  ContactElements e;
  double rnd() {
    z = z * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }
  template <class Centre>
  ElementBodies(std::uint64_t seed, std::size_t bodies, std::size_t owned, Centre&& centre) : z(seed), mass(bodies, 1.0) {
    for (std::size_t i = 0; i < bodies; ++i) {
      const std::array<double, 3> c = centre(i, [this] { return rnd(); });
      for (std::size_t k = 0; k < per_body; ++k) {
        for (int d = 0; d < 3; ++d) x.push_back(c[static_cast<std::size_t>(d)] + 8e-4 * (rnd() - 0.5));
        radius.push_back(r);
        key.push_back(static_cast<std::int64_t>(((i * 7919) % 1009) * per_body + k));
        body.push_back(static_cast<std::int32_t>(i));
      }
    }
    e.size = bodies * per_body;
    e.owned = owned * per_body;
    e.x = x.data();
    e.radius = radius.data();
    e.key = key.data();
    e.body = body.data();
    e.body_mass = mass.data();
  }
};

// Elements of bodies, as shaped grains give them: many of one body share a cell (the whole list
// skips a body's run in a cell at once), and no pair of one body is listed. Against brute force,
// from a build and from a relist with every body stale.
TEST(NeighborList, ElementsOfBodiesEqualBruteForce) {
  const std::size_t bodies = 300;
  const double r = ElementBodies::r, skin = 8e-5, L = 0.01;
  ElementBodies eb(777, bodies, 240, [&](std::size_t, auto rnd) {
    const double cx = L * rnd(), cy = L * rnd();
    return std::array<double, 3>{cx, cy, L * rnd()};
  });
  std::vector<double>& x = eb.x;
  const auto& body = eb.body;
  const auto& key = eb.key;
  ContactElements& e = eb.e;
  auto rnd = [&eb] { return eb.rnd(); };
  std::set<PairKey> expected;
  std::size_t same_body_near = 0;
  for (std::size_t a = 0; a < e.size; ++a)
    for (std::size_t b = a + 1; b < e.size; ++b) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) r2 += (x[3 * a + d] - x[3 * b + d]) * (x[3 * a + d] - x[3 * b + d]);
      const double cut = 2 * r + skin;
      if (r2 >= cut * cut) continue;
      if (body[a] == body[b]) {
        ++same_body_near;
        continue;
      }
      if (a >= e.owned && b >= e.owned) continue;
      expected.insert(pair_key(key[a], key[b]));
    }
  ASSERT_GT(same_body_near, 5 * bodies);  // a body's elements crowd its cells
  ASSERT_GT(expected.size(), 200u);
  NeighborList list;
  list.build(e, skin, {});
  EXPECT_EQ(std::set<PairKey>(list.keys.begin(), list.keys.end()), expected);
  EXPECT_EQ(list.size(), expected.size());
  for (std::size_t k = 0; k < list.size(); ++k) EXPECT_NE(body[list.first[k]], body[list.second[k]]);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] += 1e-5 * (rnd() - 0.5);  // all move a little: all stale
  expected.clear();
  for (std::size_t a = 0; a < e.size; ++a)
    for (std::size_t b = a + 1; b < e.size; ++b) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) r2 += (x[3 * a + d] - x[3 * b + d]) * (x[3 * a + d] - x[3 * b + d]);
      const double cut = 2 * r + skin;
      if (r2 < cut * cut && body[a] != body[b] && (a < e.owned || b < e.owned)) expected.insert(pair_key(key[a], key[b]));
    }
  EXPECT_TRUE(list.relist(e, skin, std::vector<char>(bodies, 1), std::vector<double>(bodies, 1e-5)));
  EXPECT_EQ(std::vector<PairKey>(expected.begin(), expected.end()), list.keys);
}

// Theory T5b: ghost elements beyond the near box are left out of the cells, and the list is the same.
// A ghost body left out at the bin that comes, relisted again and again (each time by less than s/2,
// as a run's ghosts do), within reach of owned elements is found, both from its own search and from
// a stale owned element's (the moved elements' cells).
TEST(NeighborList, GhostsLeftOutFarFromTheSubBoxAreFoundWhenTheyComeNear) {
  const std::size_t per_body = ElementBodies::per_body, owned_bodies = 200, bodies = 320;
  const double r = ElementBodies::r, skin = 8e-5, L = 0.006, face = 0.005;
  const double reach = 4e-4 * std::sqrt(3.0) + r, margin = reach + r + 3 * skin;  // DemSolver's rule
  ElementBodies eb(4242, bodies, owned_bodies, [&](std::size_t i, auto rnd) {  // owned centres in x < face
    const double cx = i < owned_bodies ? face * rnd() : face + 3e-3 * rnd(), cy = L * rnd();
    return std::array<double, 3>{cx, cy, L * rnd()};
  });
  std::vector<double>& x = eb.x;
  const auto& body = eb.body;
  const auto& key = eb.key;
  ContactElements& e = eb.e;
  auto brute = [&] {
    std::vector<PairKey> out;
    for (std::size_t a = 0; a < e.owned; ++a)
      for (std::size_t b = a + 1; b < e.size; ++b) {
        double r2 = 0;
        for (int d = 0; d < 3; ++d) r2 += (x[3 * a + d] - x[3 * b + d]) * (x[3 * a + d] - x[3 * b + d]);
        if (r2 < (2 * r + skin) * (2 * r + skin) && body[a] != body[b]) out.push_back(pair_key(key[a], key[b]));
      }
    std::sort(out.begin(), out.end());
    return out;
  };
  NeighborList all, near;
  all.build(e, skin, {});
  e.near_hi.x = face + margin;
  near.build(e, skin, {});
  EXPECT_EQ(all.left_out, 0u);
  EXPECT_GT(near.left_out, e.size / 8);  // a third of the ghost elements
  EXPECT_EQ(near.keys, all.keys);
  EXPECT_EQ(near.keys, brute());
  // A ghost body left out whole at the bin, of a high key (its owned partners search it from their
  // side), walks towards the owned ones, 0.4 s a relist.
  std::size_t g = 0;
  for (std::size_t i = owned_bodies; i < bodies; ++i)
    if (x[3 * per_body * i] > face + margin + 4e-4 && (g == 0 || key[per_body * i] > key[per_body * g])) g = i;
  ASSERT_GT(g, 0u);
  std::vector<char> stale(bodies, 0);
  std::vector<double> travel(bodies, 0.0);
  stale[g] = 1;
  int steps = 0;
  while (x[3 * per_body * g] > face - 1e-4) {
    for (std::size_t k = 0; k < per_body; ++k) x[3 * (per_body * g + k)] -= 0.4 * skin;
    travel[g] = 0.4 * skin;
    EXPECT_FALSE(near.relist(e, skin, stale, travel));
    ++steps;
  }
  EXPECT_GT(steps, 20);
  const auto found = brute();
  std::size_t with_g = 0;
  for (const auto k : found) with_g += (k >> 32) / per_body == static_cast<std::uint64_t>(key[per_body * g]) / per_body ||
                                       (k & 0xffffffffULL) / per_body == static_cast<std::uint64_t>(key[per_body * g]) / per_body;
  EXPECT_GT(with_g, 3u);  // it has owned partners now
  EXPECT_EQ(near.keys, found);
  // Now owned bodies near it are stale too: each pair from the lower key's side.
  std::size_t stale_owned = 0;
  for (std::size_t i = 0; i < owned_bodies; ++i) {
    double r2 = 0;
    for (int d = 0; d < 3; ++d) r2 += std::pow(x[3 * per_body * i + d] - x[3 * per_body * g + d], 2);
    if (r2 < 1.5e-3 * 1.5e-3) stale[i] = 1, ++stale_owned;
  }
  ASSERT_GT(stale_owned, 2u);
  ASSERT_LT(8 * (stale_owned + 2) * per_body, e.size);  // not all binned again
  for (std::size_t i = 0; i < bodies; ++i)
    if (stale[i] && i != g)
      for (std::size_t k = 0; k < per_body; ++k) x[3 * (per_body * i + k) + 1] += 1e-5;
  for (std::size_t i = 0; i < bodies; ++i) travel[i] = stale[i] ? 1e-5 : 0.0;
  travel[g] = 0;
  EXPECT_FALSE(near.relist(e, skin, stale, travel));
  EXPECT_EQ(near.keys, brute());
}

}  // namespace
}  // namespace tessera
