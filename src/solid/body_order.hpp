// SPDX-License-Identifier: MIT
// The bodies' permanent order keys (ParticleStore::order) and the storage order that follows them.
// A body's key is its rank in a global Morton (Z-order) sort of the initial positions, ties broken
// by id: neighbours in space are close in memory whatever ids a data file uses, and contact
// orientation and force summation follow the keys, the same on every decomposition (docs/design.md,
// "Parallel model", rule 0).
#pragma once
#include "core/decomposition.hpp"
#include "solid/particles.hpp"

namespace tessera {

// Collective: every owned body's key, from a sort of all bodies gathered on rank 0 (16 bytes each).
void assign_morton_order(ParticleStore& p, const Decomposition& decomp);
// Reorders the owned bodies by key (ghosts are dropped: call before building them).
void sort_owned_by_order(ParticleStore& p);

}  // namespace tessera
