// SPDX-License-Identifier: MIT
// Pass 1 of the pair loop, scalar: which listed pairs touch, compacted in list order. One loop for
// every mirror layout (pair_contacts.cpp's 3D mirrors, disc_overlaps.cpp's tail and fallback); the
// layout gives only its overlap test.
//
// Branch-free: in a dense bed about half the listed pairs touch, at random, which a branch would
// mispredict. Contacts that opened since the last evaluation with the springs advancing lose their
// history (T3): a pair that touched then (was[k]) and does not now. Rare, so that branch is
// predicted. was = nullptr: the springs stay.
#pragma once
#include <cstddef>
#include <cstdint>

namespace tessera {

// Partners are scattered over ~1000 bodies, and a large bed's mirrors come from memory: pass 1
// spends a few ns a pair, so it looks further ahead than pass 2.
inline constexpr std::size_t kTouchingPrefetch = 64;

// Pairs [begin, np) appended to out[count...]; returns the new count. out needs room for np + 8
// (a vector block stores 8).
template <class Mirror, class Touch>
std::size_t find_touching_scalar(const Mirror* mirrors, const std::int32_t* first, const std::int32_t* second,
                                 std::size_t begin, std::size_t np, std::size_t count, std::int32_t* out,
                                 std::uint8_t* was, double* hist, Touch touch) {
  for (std::size_t k = begin; k < np; ++k) {
    if (k + kTouchingPrefetch < np) __builtin_prefetch(&mirrors[second[k + kTouchingPrefetch]]);
    out[count] = static_cast<std::int32_t>(k);
    const bool t = touch(mirrors[first[k]], mirrors[second[k]]);
    count += t ? 1 : 0;
    if (was) {
      if (was[k] && !t) hist[3 * k] = hist[3 * k + 1] = hist[3 * k + 2] = 0.0;
      was[k] = t ? 1 : 0;
    }
  }
  return count;
}

}  // namespace tessera
