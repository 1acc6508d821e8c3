// SPDX-License-Identifier: MIT
#include "core/exact_sum.hpp"

#include <bit>
#include <cmath>
#include <vector>

namespace tessera {

namespace {
// A digit takes at most 2^32 per term: 2^30 terms keep every limb far below 2^63.
constexpr int kNormaliseEvery = 1 << 30;
constexpr std::int64_t kMask = 0xffffffffLL;
__extension__ typedef unsigned __int128 U128;  // GCC and Clang: 128-bit integers for the shifts
}  // namespace

void ExactSum::add(double x) {
  if (x == 0.0) return;
  if (!std::isfinite(x)) {
    nonfinite_ += x;
    return;
  }
  // x = m 2^(s - 1074) with the integer significand m < 2^53 and s in [0, 2045].
  const auto bits = std::bit_cast<std::uint64_t>(x);
  const int field = static_cast<int>((bits >> 52) & 0x7ff);
  std::uint64_t m = bits & ((std::uint64_t{1} << 52) - 1);
  int s = 0;
  if (field > 0) m |= std::uint64_t{1} << 52, s = field - 1;
  const U128 shifted = static_cast<U128>(m) << (s % 32);
  const int k = s / 32;
  const auto d0 = static_cast<std::int64_t>(shifted & kMask);
  const auto d1 = static_cast<std::int64_t>((shifted >> 32) & kMask);
  const auto d2 = static_cast<std::int64_t>(shifted >> 64);
  if (bits >> 63)
    digits_[k] -= d0, digits_[k + 1] -= d1, digits_[k + 2] -= d2;
  else
    digits_[k] += d0, digits_[k + 1] += d1, digits_[k + 2] += d2;
  if (++pending_ >= kNormaliseEvery) normalise();
}

void ExactSum::normalise() {
  // Carries upward: every digit but the top one ends in [0, 2^32); the top one holds the sign.
  for (int k = 0; k + 1 < kDigits; ++k) {
    const std::int64_t carry = digits_[k] >> 32;  // floor division by 2^32
    digits_[k] -= carry * (kMask + 1);
    digits_[k + 1] += carry;
  }
  pending_ = 0;
}

ExactSum& ExactSum::operator+=(const ExactSum& o) {
  ExactSum b = o;
  b.normalise();
  normalise();
  for (int k = 0; k < kDigits; ++k) digits_[k] += b.digits_[k];
  nonfinite_ += b.nonfinite_;
  pending_ = 2;
  return *this;
}

double ExactSum::value() const {
  ExactSum a = *this;
  a.normalise();
  bool negative = a.digits_[kDigits - 1] < 0;
  if (negative) {
    for (auto& d : a.digits_) d = -d;
    a.normalise();
  }
  int top = kDigits - 1;
  while (top >= 0 && a.digits_[top] == 0) --top;
  double r = 0;
  if (top >= 0) {
    // Correct rounding (to nearest, ties to even): the three leading digits hold 65 to 96
    // significant bits; any lower nonzero digit only breaks a tie.
    auto digit = [&](int k) { return k >= 0 ? static_cast<U128>(a.digits_[k]) : 0; };
    const U128 n = digit(top) << 64 | digit(top - 1) << 32 | digit(top - 2);
    bool sticky = false;
    for (int k = top - 3; k >= 0; --k) sticky = sticky || a.digits_[k] != 0;
    int length = 0;
    while (length < 128 && (n >> length) != 0) ++length;
    const int shift = length - 53;
    auto mantissa = static_cast<std::uint64_t>(n >> shift);
    const U128 rest = n & ((static_cast<U128>(1) << shift) - 1);
    const U128 half = static_cast<U128>(1) << (shift - 1);
    if (rest > half || (rest == half && (sticky || (mantissa & 1)))) ++mantissa;
    r = std::ldexp(static_cast<double>(mantissa), shift + 32 * (top - 2) - 1074);
  }
  if (negative) r = -r;
  return nonfinite_ != 0.0 || std::isnan(nonfinite_) ? nonfinite_ + r : r;
}

void ExactSum::all_reduce(std::span<ExactSum> sums, MPI_Comm comm) {
  // One message: the digits, and a count of the sums holding a non-finite term; those terms travel
  // in a second message only when some rank has one.
  const std::size_t n = sums.size() * kDigits;
  thread_local std::vector<std::int64_t> digits;  // kept: the DEM sums its replicated loads every step
  digits.assign(n + 1, 0);
  for (std::size_t i = 0; i < sums.size(); ++i) {
    sums[i].normalise();
    for (int k = 0; k < kDigits; ++k) digits[i * kDigits + k] = sums[i].digits_[k];
    if (sums[i].nonfinite_ != 0.0 || std::isnan(sums[i].nonfinite_)) ++digits[n];
  }
  // Normalised digits are below 2^32: a sum over up to 2^30 ranks cannot overflow.
  MPI_Allreduce(MPI_IN_PLACE, digits.data(), static_cast<int>(digits.size()), MPI_INT64_T, MPI_SUM, comm);
  if (digits[n] > 0) {
    std::vector<double> nonfinite(sums.size());
    for (std::size_t i = 0; i < sums.size(); ++i) nonfinite[i] = sums[i].nonfinite_;
    MPI_Allreduce(MPI_IN_PLACE, nonfinite.data(), static_cast<int>(nonfinite.size()), MPI_DOUBLE, MPI_SUM, comm);
    for (std::size_t i = 0; i < sums.size(); ++i) sums[i].nonfinite_ = nonfinite[i];
  }
  for (std::size_t i = 0; i < sums.size(); ++i) {
    for (int k = 0; k < kDigits; ++k) sums[i].digits_[k] = digits[i * kDigits + k];
    sums[i].normalise();
  }
}

void ExactSum::all_reduce(MPI_Comm comm) { all_reduce(std::span<ExactSum>(this, 1), comm); }

double exact_sum(std::span<const double> values) {
  ExactSum s;
  for (const double v : values) s.add(v);
  return s.value();
}

}  // namespace tessera
