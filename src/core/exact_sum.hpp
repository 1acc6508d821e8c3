// SPDX-License-Identifier: MIT
// Order-independent sums of doubles, for reported quantities that must not depend on the rank
// count (kinetic energy, wall loads, packing fraction) and, later, fluid forces summed over ranks.
//
// A floating-point sum depends on the order of its terms: the same bodies summed per rank and then
// across ranks round differently on 1, 2 and 4 ranks. ExactSum keeps the sum without rounding, as
// an integer multiple of 2^-1074 (the smallest double) held in 32-bit digits of int64 limbs (a
// superaccumulator, Kulisch's long accumulator in software): every double is such a multiple, so
// adding is exact and the total is the same in any order. `value()` rounds it once, to nearest
// (ties to even) from the carry-normalised digits, so the result is the same bits
// whatever the order or the rank count. Non-finite terms are kept aside and make the value NaN or
// infinite as an ordinary sum would.
//
// Cost: a few integer operations per term (about 5 ns); meant for reductions at output intervals
// and per-body totals, not for inner contact loops.
#pragma once
#include <mpi.h>

#include <array>
#include <cstdint>
#include <span>

namespace tessera {

class ExactSum {
 public:
  ExactSum() { digits_.fill(0); }
  void add(double x);
  ExactSum& operator+=(double x) {
    add(x);
    return *this;
  }
  ExactSum& operator+=(const ExactSum& o);
  // The exact total rounded to a double (the same bits for the same exact total).
  double value() const;
  // Collective: every rank's sum becomes the sum over all ranks of `comm`.
  void all_reduce(MPI_Comm comm);
  // Collective over `comm`: each entry of `sums` becomes its sum over all ranks (one message).
  static void all_reduce(std::span<ExactSum> sums, MPI_Comm comm);

  // 2^-1074 ... 2^1024 plus headroom, in 32-bit digits.
  static constexpr int kDigits = 68;

 private:
  void normalise();
  std::array<std::int64_t, kDigits> digits_;
  double nonfinite_ = 0;  // sum of the infinite and NaN terms (0 when there is none)
  int pending_ = 0;       // terms added since the last normalisation
};

// The order-independent sum of a span of values (convenience).
double exact_sum(std::span<const double> values);

}  // namespace tessera
