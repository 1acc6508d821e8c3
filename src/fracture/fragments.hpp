// SPDX-License-Identifier: MIT
// The fragments of a bonded block (docs/theory.md B8a): the sets of elements joined through intact
// bonds, found by union-find over the bonds. Labels are numbered by each fragment's lowest element
// and masses summed in element order, so every rank, holding the same broken flags, finds the same
// fragments to the bit. Fragments only split (bonds never heal).
#pragma once
#include <vector>

#include "fracture/bonded_block.hpp"

namespace tessera {

struct Fragments {
  std::vector<int> label;     // per element: its fragment, 0 .. count - 1
  std::vector<double> mass;   // per fragment
  std::vector<int> parent;    // union-find storage, reused
  int count() const { return static_cast<int>(mass.size()); }
};

// broken: per bond, nonzero when released.
void find_fragments(const BondedBlock& block, const std::vector<char>& broken, Fragments& out);

}  // namespace tessera
