// SPDX-License-Identifier: MIT
// ExactSum (src/core/exact_sum.hpp): sums that do not depend on the order of their terms or on the
// rank count. References are exact by construction (cancelling terms, integers, powers of two),
// not taken from the code under test.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "core/exact_sum.hpp"

namespace {

using tessera::ExactSum;

std::vector<double> spread_values(std::size_t n, std::uint64_t seed) {
  // Magnitudes over 30 decades and both signs: an ordinary sum of these depends on the order.
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-50, 50);
  std::vector<double> v(n);
  for (auto& x : v) x = std::ldexp(mantissa(rng), exponent(rng));
  return v;
}

TEST(ExactSum, CancellationThatPlainSumsLose) {
  // 1e16 + 1 - 1e16: a double sum in this order gives 0 (1e16 + 1 rounds to 1e16); the exact sum is 1.
  ExactSum s;
  s += 1e16, s += 1.0, s += -1e16;
  EXPECT_EQ(s.value(), 1.0);
  // Opposite pairs of every magnitude leave exactly the one term that has no partner.
  const auto v = spread_values(10000, 7);
  ExactSum t;
  for (const double x : v) t += x;
  t += std::ldexp(1.0, -1000);
  for (const double x : v) t += -x;
  EXPECT_EQ(t.value(), std::ldexp(1.0, -1000));
}

TEST(ExactSum, IntegersAndExtremes) {
  ExactSum s;
  for (int i = 1; i <= 100000; ++i) s += static_cast<double>(i);
  EXPECT_EQ(s.value(), 100000.0 * 100001.0 / 2.0);
  ExactSum tiny;
  const double denormal = std::numeric_limits<double>::denorm_min();
  for (int i = 0; i < 1024; ++i) tiny += denormal;
  EXPECT_EQ(tiny.value(), 1024 * denormal);
  ExactSum big;
  big += std::numeric_limits<double>::max(), big += -std::numeric_limits<double>::max(), big += -3.5;
  EXPECT_EQ(big.value(), -3.5);
  ExactSum zero;
  zero += 0.0, zero += -0.0;
  EXPECT_EQ(zero.value(), 0.0);
}

TEST(ExactSum, NonFiniteTermsPropagate) {
  ExactSum s;
  s += 1.0, s += std::numeric_limits<double>::infinity();
  EXPECT_EQ(s.value(), std::numeric_limits<double>::infinity());
  s += std::nan("");
  EXPECT_TRUE(std::isnan(s.value()));
}

TEST(ExactSum, OrderDoesNotChangeABit) {
  auto v = spread_values(50000, 11);
  ExactSum a;
  for (const double x : v) a += x;
  std::mt19937_64 rng(3);
  std::shuffle(v.begin(), v.end(), rng);
  ExactSum b;
  for (const double x : v) b += x;
  EXPECT_EQ(std::bit_cast<std::uint64_t>(a.value()), std::bit_cast<std::uint64_t>(b.value()));
  // The plain sums of the two orders differ (what makes this test meaningful).
  const double plain_a = std::accumulate(v.rbegin(), v.rend(), 0.0), plain_b = std::accumulate(v.begin(), v.end(), 0.0);
  EXPECT_NE(plain_a, plain_b);
  // The rounded exact sum is within one unit in the last place of the long-double sum.
  long double ref = 0;
  for (const double x : v) ref += x;
  EXPECT_NEAR(a.value(), static_cast<double>(ref), 2 * std::abs(a.value()) * std::numeric_limits<double>::epsilon());
  // Merging partial sums gives the same bits as one sum.
  ExactSum first, second;
  for (std::size_t i = 0; i < v.size(); ++i) (i % 3 ? first : second) += v[i];
  first += second;
  EXPECT_EQ(std::bit_cast<std::uint64_t>(first.value()), std::bit_cast<std::uint64_t>(a.value()));
}

TEST(ExactSum, AllReduceIndependentOfRankCount) {
  // Every rank takes an interleaved share of the same terms: the reduced sum equals the serial one.
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const auto v = spread_values(20000, 5);
  ExactSum serial;
  for (const double x : v) serial += x;
  ExactSum parts[2];
  for (std::size_t i = static_cast<std::size_t>(rank); i < v.size(); i += static_cast<std::size_t>(size))
    parts[0] += v[i], parts[1] += -2.0 * v[i];
  ExactSum::all_reduce(parts, MPI_COMM_WORLD);
  EXPECT_EQ(std::bit_cast<std::uint64_t>(parts[0].value()), std::bit_cast<std::uint64_t>(serial.value()));
  EXPECT_EQ(parts[1].value(), -2.0 * serial.value());
}

// The non-finite terms travel only when some rank has one (a second message): an infinity on the
// last rank alone reaches every rank's sum, and the finite sums beside it stay exact.
TEST(ExactSum, AllReduceCarriesANonFiniteTermFromOneRank) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  ExactSum parts[2];
  parts[0] += 1.0;
  parts[1] += 0.5;
  if (rank == size - 1) parts[0] += -std::numeric_limits<double>::infinity();
  ExactSum::all_reduce(parts, MPI_COMM_WORLD);
  EXPECT_EQ(parts[0].value(), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(parts[1].value(), 0.5 * size);
  ExactSum finite[1];
  finite[0] += 0.25;
  ExactSum::all_reduce(finite, MPI_COMM_WORLD);
  EXPECT_EQ(finite[0].value(), 0.25 * size);
}

}  // namespace
