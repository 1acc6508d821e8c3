// SPDX-License-Identifier: MIT
// Helpers the multigrid's files share (cell_multigrid.cpp, cell_multigrid_coarsest.cpp).
#pragma once
#include <array>
#include <cstddef>

namespace tessera::multigrid_detail {

// fn(i, j, k) over the box [s, s + m), x fastest.
template <class F>
void for_owned(const std::array<int, 3>& s, const std::array<int, 3>& m, F&& fn) {
  for (int k = s[2]; k < s[2] + m[2]; ++k)
    for (int j = s[1]; j < s[1] + m[1]; ++j)
      for (int i = s[0]; i < s[0] + m[0]; ++i) fn(i, j, k);
}

// The sum of cell c's six face coefficients (an outflow face's included), in a fixed order.
template <class Level>
double coefficient_sum(const Level& L, std::size_t c) {
  double s = 0;
  for (int d = 0; d < 3; ++d) s += double(L.coef[d][c]) + double(L.coef[d][c + L.stride[d]]);
  return s;
}

}  // namespace tessera::multigrid_detail
