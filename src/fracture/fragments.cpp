// SPDX-License-Identifier: MIT
#include "fracture/fragments.hpp"

#include <algorithm>

namespace tessera {

namespace {

int root(std::vector<int>& parent, int e) {
  while (parent[static_cast<std::size_t>(e)] != e) {
    int& p = parent[static_cast<std::size_t>(e)];
    p = parent[static_cast<std::size_t>(p)];  // path halving
    e = p;
  }
  return e;
}

}  // namespace

void find_fragments(const BondedBlock& block, const std::vector<char>& broken, Fragments& out) {
  const std::size_t n = block.size();
  std::vector<int>& parent = out.parent;
  parent.resize(n);
  for (std::size_t e = 0; e < n; ++e) parent[e] = static_cast<int>(e);
  for (std::size_t b = 0; b < block.bonds.size(); ++b) {
    if (broken[b]) continue;
    const int a = root(parent, block.bonds[b].master), c = root(parent, block.bonds[b].slave);
    if (a != c) parent[static_cast<std::size_t>(std::max(a, c))] = std::min(a, c);  // the lower index is the root
  }
  // Every root is its fragment's lowest element: labels in order of first appearance.
  out.label.assign(n, -1);
  out.mass.clear();
  for (std::size_t e = 0; e < n; ++e) {
    const std::size_t r = static_cast<std::size_t>(root(parent, static_cast<int>(e)));
    if (r == e) {
      out.label[e] = static_cast<int>(out.mass.size());
      out.mass.push_back(0);
    } else {
      out.label[e] = out.label[r];
    }
    out.mass[static_cast<std::size_t>(out.label[e])] += block.mass[e];
  }
}

}  // namespace tessera
