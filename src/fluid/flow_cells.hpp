// SPDX-License-Identifier: MIT
// What the flow solver's source files share about cells (not part of its interface).
#pragma once
#include <array>

namespace tessera::flow_cells {

// Cells with f below kEmpty or above 1 - kEmpty carry no interface (round-off residue of the
// split advection; their volume stays counted, none is clipped).
constexpr double kEmpty = 1e-12;

// Loops over a box of global indices [lo, hi) in k, j, i order.
template <class F>
void for_box(const std::array<int, 3>& lo, const std::array<int, 3>& hi, F&& fn) {
  for (int k = lo[2]; k < hi[2]; ++k)
    for (int j = lo[1]; j < hi[1]; ++j)
      for (int i = lo[0]; i < hi[0]; ++i) fn(i, j, k);
}

}  // namespace tessera::flow_cells
