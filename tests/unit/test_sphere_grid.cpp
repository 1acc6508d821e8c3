// SPDX-License-Identifier: MIT
// The blast's sphere grid (src/fracture/sphere_grid.hpp) against brute force: a query reports every
// sphere within r_a + r_b + pad exactly once, over radii spanning 40 times (more classes than the
// grid keeps), spheres far outside the others (a flung fragment), moved spheres (their old entries
// never reported), and the build's "coarser only" query finding each pair once from its smaller
// sphere.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <vector>

#include "fracture/sphere_grid.hpp"

namespace tessera {
namespace {

struct Cloud {
  std::vector<Vec3> at;
  std::vector<double> r;
};

Cloud make_cloud(std::size_t n, double r_max, double spread) {
  std::uint64_t z = 777;
  auto rnd = [&z] {
    z = z * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  };
  Cloud c;
  for (std::size_t i = 0; i < n; ++i) {
    // Log-uniform radii from r_max / 40 to r_max; positions in a box a few largest spheres wide.
    c.r.push_back(r_max * std::pow(40.0, -rnd()));
    c.at.push_back({spread * rnd() - 0.3 * spread, spread * rnd(), 0.2 * spread * rnd()});
  }
  c.at.push_back({50.0, -20.0, 3.0});  // flung far away, next to one other
  c.r.push_back(0.5 * r_max);
  c.at.push_back({50.0 + 0.5 * r_max, -20.0, 3.0});
  c.r.push_back(0.01 * r_max);
  return c;
}

// Every sphere of the cloud in a grid whose classes reach down to r_small (r_small = 1.5 r_max: one class).
SphereGrid grid_of(const Cloud& c, double r_max, double r_small, double pad) {
  SphereGrid g;
  g.reset(1.5 * r_max, r_small, pad);
  for (std::size_t s = 0; s < c.at.size(); ++s) g.insert(static_cast<int>(s), c.at[s], c.r[s]);
  return g;
}

std::set<int> brute(const Cloud& c, std::size_t a, double pad) {
  std::set<int> out;
  for (std::size_t b = 0; b < c.at.size(); ++b) {
    const double reach = c.r[a] + c.r[b] + pad;
    if (b != a && norm2(c.at[a] - c.at[b]) < reach * reach) out.insert(static_cast<int>(b));
  }
  return out;
}

TEST(SphereGrid, AQueryReportsEverySphereWithinReachOnce) {
  const double r_max = 0.01, pad = 4e-4;
  Cloud c = make_cloud(3000, r_max, 0.15);
  SphereGrid g = grid_of(c, r_max, r_max / 40, pad);
  std::size_t found = 0, reported = 0;
  for (std::size_t a = 0; a < c.at.size(); ++a) {
    std::map<int, int> seen;
    g.near(c.at[a], c.r[a], false, [&](int b) { ++seen[b]; });
    reported += seen.size();
    for (const auto& [b, k] : seen) ASSERT_EQ(k, 1) << "sphere " << b << " reported twice to " << a;
    for (int b : brute(c, a, pad)) {
      ASSERT_TRUE(seen.count(b)) << "sphere " << b << " (r " << c.r[b] << ") missed from " << a << " (r " << c.r[a] << ")";
      ++found;
    }
  }
  EXPECT_GT(found, 3000u);  // the cloud is dense enough that most spheres have partners
  // The point of the classes: far fewer candidates than one class, cells of the largest spheres.
  SphereGrid one = grid_of(c, r_max, 1.5 * r_max, pad);
  std::size_t reported_one = 0;
  for (std::size_t a = 0; a < c.at.size(); ++a) one.near(c.at[a], c.r[a], false, [&](int) { ++reported_one; });
  std::printf("candidates: %zu with classes, %zu with one class; %zu within reach\n", reported, reported_one, found);
  EXPECT_LT(3 * reported, reported_one) << "classes " << reported << " candidates, one class " << reported_one;
}

TEST(SphereGrid, CoarserOnlyQueriesFindEachPairOnceFromItsSmallerSphere) {
  const double r_max = 0.01, pad = 4e-4;
  Cloud c = make_cloud(2000, r_max, 0.12);
  SphereGrid g = grid_of(c, r_max, r_max / 40, pad);
  std::set<std::pair<int, int>> expected, got;
  for (std::size_t a = 0; a < c.at.size(); ++a)
    for (int b : brute(c, a, pad))
      if (static_cast<int>(a) < b) expected.insert({static_cast<int>(a), b});
  for (std::size_t a = 0; a < c.at.size(); ++a) {
    const int ia = static_cast<int>(a), cls = g.size_class(c.r[a]);
    g.near(c.at[a], c.r[a], true, [&](int b) {
      if (b == ia || (b < ia && g.size_class(c.r[static_cast<std::size_t>(b)]) == cls)) return;
      const double reach = c.r[a] + c.r[static_cast<std::size_t>(b)] + pad;
      if (norm2(c.at[a] - c.at[static_cast<std::size_t>(b)]) >= reach * reach) return;
      ASSERT_TRUE(got.insert({std::min(ia, b), std::max(ia, b)}).second) << "pair " << ia << "-" << b << " twice";
    });
  }
  EXPECT_EQ(got, expected);
}

TEST(SphereGrid, MovedSpheresAreFoundWhereTheyAreNowOnly) {
  const double r_max = 0.01, pad = 4e-4;
  Cloud c = make_cloud(1500, r_max, 0.1);
  SphereGrid g = grid_of(c, r_max, r_max / 40, pad);
  // Move every third sphere several times (enough old entries to be dropped more than once).
  for (int round = 0; round < 4; ++round)
    for (std::size_t s = static_cast<std::size_t>(round) % 3; s < c.at.size(); s += 3) {
      c.at[s] = c.at[s] + Vec3{0.013 * (round + 1), -0.007, 0.002 * round};
      g.move(static_cast<int>(s), c.at[s], c.r[s]);
    }
  for (std::size_t a = 0; a < c.at.size(); ++a) {
    std::map<int, int> seen;
    g.near(c.at[a], c.r[a], false, [&](int b) { ++seen[b]; });
    for (const auto& [b, k] : seen) ASSERT_EQ(k, 1) << "sphere " << b << " reported twice (an old entry?)";
    for (int b : brute(c, a, pad)) ASSERT_TRUE(seen.count(b)) << "moved sphere " << b << " missed from " << a;
  }
}

}  // namespace
}  // namespace tessera
