// SPDX-License-Identifier: MIT
// The DEM's wall stage: contacts of the owned entities (contact_entities.hpp) with the static walls
// of planes and boxes (walls.hpp; the wall law, T7: m* = m, R* = R). It owns the list of (entity,
// wall slot) entries within reach at the last rebuild (no other entity can touch a wall before the
// next one: bodies move less than skin/2 in between), their coefficient sets, the force each entry
// put on its wall at the last evaluation, and the walls' impulse when asked for it.
// Springs: sphere bodies keep theirs in ParticleStore::wall_history (per body and slot, they travel
// with the body); contact spheres of shaped bodies per entry, keyed by (element key, slot)
// (contact_history.hpp wall_key), carried over rebuilds by a merge of sorted keys.
#pragma once
#include <mpi.h>

#include <array>
#include <cstdint>
#include <vector>

#include "core/exact_sum.hpp"
#include "solid/contact_entities.hpp"
#include "solid/contact_history.hpp"
#include "solid/walls.hpp"

namespace tessera {

class PlaneWallContacts {
 public:
  // The entities of the entries (sorted, an entity once per wall it may touch).
  const std::vector<std::int32_t>& entities() const { return entity_; }
  // At a rebuild: the entries within radius + skin of the owned entities, in (entity, slot) order;
  // shaped mode: each with its spring from the previous list, else from `extra`, else zero.
  void find(const ContactEntities& entities, const Walls& walls, double skin, const HistoryMap& extra);
  // After a relist (shaped mode): the entries of the stale bodies' entities found again, the
  // others kept as they are.
  void refind(const ContactEntities& entities, const Walls& walls, double skin, const std::vector<char>& stale_body);
  // The coefficient set of each entry: lookup(material a, material b, m*, R*) -> index.
  template <class Lookup>
  void fill_coefficients(const ContactEntities& entities, const Walls& walls, Lookup&& lookup) {
    const auto& prims = walls.primitives();
    coefficient_.resize(entity_.size());
    for (std::size_t k = 0; k < entity_.size(); ++k) {
      const std::size_t e = entity_[k];
      coefficient_[k] =
          lookup(entities.material(e), prims[slot_[k]].material, entities.mass(e), entities.radius(e));
    }
  }
  // This step's forces into the entities' contact buffer (dt = 0: springs unchanged).
  void forces(ContactEntities& entities, ParticleStore& bodies, const Walls& walls, ContactLanes& lanes,
              const ContactCoefficients* sets, LawKind law, double dt);

  // Collective: the total force of all bodies on each wall primitive at the last evaluation, summed
  // exactly (the same bits on any rank count).
  std::vector<Vec3> loads(const Walls& walls, MPI_Comm comm) const;
  // The impulse the walls gave the owned bodies: add_half_impulse(dt) after each evaluation that a
  // half-kick applies (dt/2 times the push now).
  void track_impulse(bool on);
  bool tracking_impulse() const { return track_impulse_; }
  void add_half_impulse(double dt);
  Vec3 impulse(MPI_Comm comm) const;  // collective, exact

  // Shaped mode: the springs of the entries (touching ones), all or those of bodies leaving.
  void collect(HistoryMap& h) const;
  void collect_leaving(const ContactEntities& entities, const std::vector<char>& leaving, HistoryMap& h) const;

 private:
  std::vector<std::int32_t> entity_, slot_, coefficient_;
  std::vector<PairKey> keys_;      // shaped mode: per entry
  std::vector<double> hist_;       // shaped mode: 3 per entry
  // The previous entries while find()/refind() make the new ones (kept: no allocation per call).
  std::vector<std::int32_t> old_entity_, old_slot_;
  std::vector<PairKey> old_keys_;
  std::vector<double> old_hist_;
  std::vector<double> entry_force_;  // 3 per entry: the body's force on the wall
  bool track_impulse_ = false;
  std::array<ExactSum, 3> impulse_;
};

}  // namespace tessera
