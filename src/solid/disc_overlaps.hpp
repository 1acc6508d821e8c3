// SPDX-License-Identifier: MIT
// Pass 1 of the pair loop for discs (plane mode, kernel_mirrors.hpp): which listed pairs overlap.
// Eight pairs at a time where the machine has AVX-512 (gathers of the two mirrors' centres and
// radii, a compare into a mask, the touching indices compressed into the output), the scalar loop
// elsewhere and for the tail. Both make the same IEEE operations in the same order as the scalar
// test (du^2 + dv^2 < (r_a + r_b)^2, no contraction), so the same pairs touch on any machine.
#pragma once
#include <cstddef>
#include <cstdint>

#include "solid/kernel_mirrors.hpp"

namespace tessera {

struct DiscOverlapPass {
  const DiscMirror* mirrors;
  const std::int32_t* first;
  const std::int32_t* second;
  std::size_t pairs;
  // Out: the touching pairs' list indices, ascending (room for pairs + 8: a block stores 8).
  std::int32_t* touching;
  // With the springs advancing: per pair, whether it touched at the last such evaluation (updated),
  // and the springs (3 per pair), cleared for a pair that touched then and does not now (T3).
  std::uint8_t* was = nullptr;
  double* history = nullptr;
};

// Returns how many pairs touch.
std::size_t find_disc_overlaps(const DiscOverlapPass& pass);

}  // namespace tessera
