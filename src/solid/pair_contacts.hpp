// SPDX-License-Identifier: MIT
// The DEM's pair stage (T1-T4): contacts between the entities (contact_entities.hpp) of the Verlet
// list (neighbor_list.hpp), in its canonical pair order. It owns the list (pairs, their springs and
// m*), each listed pair's material pair, and which listed pairs touch now and touched at the last
// evaluation that advanced the springs (a contact that opened loses its spring, T3).
//
// The loop, per evaluation: pass 1 (branch-free; discs: disc_overlaps.hpp) finds the touching pairs; pass 2 gathers them into
// lanes in blocks, evaluates the law on the lanes (contact_kernel.hpp, vectorised) and adds each
// force to its two bodies in pair order, which is canonical: the same bits on any rank count. It
// runs over either mirror layout of the kernel (3D, or discs in plane mode: kernel_mirrors.hpp).
#pragma once
#include <cstdint>
#include <vector>

#include "solid/contact_entities.hpp"
#include "solid/contact_kernel.hpp"
#include "solid/neighbor_list.hpp"

namespace tessera {

class PairContacts {
 public:
  NeighborList& list() { return list_; }
  const NeighborList& list() const { return list_; }
  // After a list build: which pairs touched, from their springs.
  void start_list();
  // The material pair of each listed pair (its index in the model's pair table): the law's
  // coefficients come from it, m* and R* in the kernel's lanes (T1-T7).
  void fill_materials(const ContactEntities& entities, const ContactModel& model);
  // This step's pair forces into the entities' contact buffer (emptied first). `packed`: the
  // leading entities whose mirrors the integrator already packed this step. dt = 0 and
  // update_history = false leave the springs and the touching flags as they are (set-up).
  void forces(ContactEntities& entities, std::size_t packed, ContactLanes& lanes, const ContactModel& model,
              double dt, bool update_history);

 private:
  struct SphereMirrors;
  template <int N>
  struct DiscMirrors;
  template <class Mirrors>
  void loop(Mirrors& view, ContactEntities& entities, std::size_t packed, ContactLanes& lanes,
            const ContactModel& model, double dt, bool update_history);

  NeighborList list_;
  std::vector<std::int32_t> material_pair_;  // per listed pair, into the model's pair table
  // Listed pairs touching now (ascending list indices); per listed pair, whether it touched at the
  // previous evaluation that advanced the springs.
  std::vector<std::int32_t> touching_;  // the first ones (as many as touch) are this evaluation's
  std::vector<std::uint8_t> was_touching_;
};

}  // namespace tessera
