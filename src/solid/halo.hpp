// SPDX-License-Identifier: MIT
// Ghosts and migration over the Cartesian process grid.
//
// Ownership rule (who does what):
// | what                               | who                                                    |
// |------------------------------------|--------------------------------------------------------|
// | integrate a body                   | the rank whose sub-box holds its centre (owner)        |
// | evaluate a contact (a, b)          | every rank that owns a or b; a rank owning both does it |
// |                                    | once; ghost-ghost pairs are never evaluated            |
// | force on a body                    | summed by its owner only, in partner-key order; a ghost |
// |                                    | copy's force is discarded (no reverse communication)   |
// | contact history (a, b)             | kept by every rank evaluating (a, b): identical copies |
// |                                    | since both evaluate the same canonical expression      |
// | history when a body migrates       | travels with it (all its pairs' entries)               |
//
// Ghosts: a body is copied to the neighbour across a face when its centre is within
// r + r_max + skin of that face; faces are swept x, then y, then z, and ghosts received in an
// earlier direction are forwarded, which fills edges and corners. Positions, velocities and angular
// velocities of ghosts are refreshed every step along the same swaps (forward()).
// Migration happens only at neighbour-list rebuilds, when no body has moved more than skin/2.
#pragma once
#include <vector>

#include "core/decomposition.hpp"
#include "solid/contact_history.hpp"
#include "solid/particles.hpp"

namespace tessera {

class Halo {
 public:
  explicit Halo(const Decomposition& decomp) : decomp_(decomp) {}

  // Owned bodies whose centre left the sub-box go to the owner, with their contact histories
  // (looked up in and added to `histories`). Ghosts are dropped first.
  void migrate(ParticleStore& p, HistoryMap& histories);
  // Rebuilds the ghost layer; `reach_extra` = r_max + skin (global maxima).
  void build_ghosts(ParticleStore& p, double reach_extra);
  // Refreshes ghost x, v, omega from their owners.
  void forward(ParticleStore& p);
  // Reverse communication: `values` holds `width` doubles per local body (owned, then ghosts);
  // each ghost's values are sent back along the swaps that brought it, in reverse order, and added
  // to its owner's (a corner ghost passes through the rank that forwarded it). Owned values end
  // up as their own plus every ghost copy's, in an order fixed by the decomposition.
  void reverse_add(std::vector<double>& values, int width);
  // The other way: every ghost's `width` values become its owner's (along the swaps, as forward()).
  void forward_values(std::vector<double>& values, int width);

  std::size_t bytes_sent() const { return bytes_sent_; }
  std::size_t migrations() const { return migrations_; }  // bodies sent to another rank, whole run

  // Shaped bodies: ghosts also need their orientation every step, and history keys are element
  // keys (body order * key_stride + sphere index; wall entries have a high part >= kWallKeyBase).
  bool forward_orientation = false;
  std::int64_t key_stride = 1;

 private:
  struct Swap {
    int dim = 0, send_rank = 0, recv_rank = 0;
    std::vector<std::int32_t> send;
    std::size_t recv_first = 0, recv_count = 0;
  };
  void exchange(int send_rank, int recv_rank, const std::vector<double>& out, std::vector<double>& in);

  const Decomposition& decomp_;
  std::vector<Swap> swaps_;
  std::vector<double> out_, in_;
  std::size_t bytes_sent_ = 0, migrations_ = 0;
};

}  // namespace tessera
