// SPDX-License-Identifier: MIT
// Pass 1 of the disc pair loop (disc_overlaps.hpp: AVX-512 where the machine has it, scalar for the
// tail and elsewhere) finds exactly the pairs the definition gives: du^2 + dv^2 < (r_a + r_b)^2,
// strictly, in list order; a pair that touched and does not now loses its spring; flags follow.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "solid/disc_overlaps.hpp"

namespace tessera {
namespace {

struct Case {
  std::vector<DiscMirror> mirrors;
  std::vector<std::int32_t> first, second;
  std::vector<std::uint8_t> was;
  std::vector<double> history;
};

Case make_case(std::size_t bodies, std::size_t pairs) {
  Case c;
  std::uint64_t z = 987654321;
  auto rnd = [&z] {
    z = z * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  };
  for (std::size_t i = 0; i < bodies; ++i) c.mirrors.push_back({rnd(), rnd(), 0.05 + 0.1 * rnd(), rnd(), rnd(), rnd()});
  for (std::size_t k = 0; k < pairs; ++k) {
    c.first.push_back(static_cast<std::int32_t>(rnd() * bodies));
    c.second.push_back(static_cast<std::int32_t>(rnd() * bodies));
    c.was.push_back(rnd() < 0.5 ? 1 : 0);
    for (int d = 0; d < 3; ++d) c.history.push_back(c.was.back() ? 1.0 + rnd() : 0.0);
  }
  // Exactly at contact (3-4-5: du^2 + dv^2 = (r_a + r_b)^2 in exact arithmetic and in doubles): not touching.
  c.mirrors[0] = {0.0, 0.0, 2.0, 0, 0, 0};
  c.mirrors[1] = {3.0, 4.0, 3.0, 0, 0, 0};
  c.first[5] = 0, c.second[5] = 1, c.was[5] = 1;
  // A hair closer: touching.
  c.mirrors[2] = {3.0, 3.999999999, 3.0, 0, 0, 0};
  c.first[9] = 0, c.second[9] = 2, c.was[9] = 0;
  return c;
}

TEST(DiscOverlaps, MatchTheDefinitionWithSpringsAndFlags) {
  for (const std::size_t pairs : {std::size_t{13}, std::size_t{1003}, std::size_t{4096}}) {
    Case c = make_case(300, pairs);
    Case expected = c;
    std::vector<std::int32_t> touching_expected;
    for (std::size_t k = 0; k < pairs; ++k) {
      const DiscMirror &a = c.mirrors[c.first[k]], &b = c.mirrors[c.second[k]];
      const double du = a.u - b.u, dv = a.v - b.v, rs = a.r + b.r;
      const bool touch = du * du + dv * dv < rs * rs;
      if (touch) touching_expected.push_back(static_cast<std::int32_t>(k));
      if (expected.was[k] && !touch)
        for (int d = 0; d < 3; ++d) expected.history[3 * k + d] = 0.0;
      expected.was[k] = touch ? 1 : 0;
    }
    ASSERT_GT(touching_expected.size(), pairs / 10);  // both outcomes are exercised
    ASSERT_LT(touching_expected.size(), pairs - pairs / 10);
    std::vector<std::int32_t> touching(pairs + 8, -1);
    const std::size_t n = find_disc_overlaps(
        {c.mirrors.data(), c.first.data(), c.second.data(), pairs, touching.data(), c.was.data(), c.history.data()});
    touching.resize(n);
    EXPECT_EQ(touching, touching_expected) << pairs << " pairs";
    EXPECT_EQ(c.was, expected.was);
    EXPECT_EQ(c.history, expected.history);
    EXPECT_EQ(std::count(touching.begin(), touching.end(), 5), 0);  // exactly at contact
    EXPECT_EQ(std::count(touching.begin(), touching.end(), 9), 1);

    // Springs not advancing (was = nullptr): the same pairs, springs and flags untouched.
    Case d = make_case(300, pairs);
    const Case before = d;
    std::vector<std::int32_t> again(pairs + 8, -1);
    const std::size_t m =
        find_disc_overlaps({d.mirrors.data(), d.first.data(), d.second.data(), pairs, again.data(), nullptr, nullptr});
    again.resize(m);
    EXPECT_EQ(again, touching_expected);
    EXPECT_EQ(d.history, before.history);
    EXPECT_EQ(d.was, before.was);
  }
}

}  // namespace
}  // namespace tessera
