// SPDX-License-Identifier: MIT
// The DEM's mesh-wall stage (T14, mesh_walls.hpp): contacts of the owned entities
// (contact_entities.hpp) with triangle-mesh walls. It owns the (entity, mesh) pairs within reach
// at the last search with their candidate triangles and coefficient sets, the meshes' nodes at that
// search (how far a moving mesh has gone since), and the tangential springs, keyed by (element key,
// mesh, contact ordinal) (contact_history.hpp mesh_key): a sphere rolling over a flat mesh keeps its
// spring across triangle edges, and the springs travel with their bodies between ranks.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "solid/contact_entities.hpp"
#include "solid/contact_history.hpp"
#include "solid/mesh_walls.hpp"
#include "solid/replicated_loads.hpp"

namespace tessera {

class MeshWallContacts {
 public:
  // Each owned entity against each mesh: the triangles within its radius + skin, found through a
  // grid of the triangles' bounding boxes.
  void find(const ContactEntities& entities, const std::vector<MeshWall>& meshes, double skin);
  // The largest node displacement since the last find.
  double displacement(const std::vector<MeshWall>& meshes) const;
  template <class Lookup>
  void fill_coefficients(const ContactEntities& entities, const std::vector<MeshWall>& meshes, Lookup&& lookup) {
    coefficient_.resize(entity_.size());
    for (std::size_t k = 0; k < entity_.size(); ++k) {
      const std::size_t e = entity_[k];
      coefficient_[k] =
          lookup(entities.material(e), meshes[mesh_of_[k]].material, entities.mass(e), entities.radius(e));
    }
  }
  // This step's contacts (the wall law with the wall's velocity at the contact point; T11's
  // de-duplication) into the entities' contact buffer; their reactions listed in `loads`; the
  // springs advanced by dt (dt = 0: unchanged). The meshes' force and moment are reset.
  void forces(ContactEntities& entities, std::vector<MeshWall>& meshes, ContactLanes& lanes,
              const ContactCoefficients* sets, LawKind law, double dt, ReplicatedLoads& loads);

  // Springs: all of them (restart, migration) and the ones that came with arriving bodies.
  const HistoryMap& springs() const { return hist_; }
  void adopt(PairKey key, const std::array<double, 3>& h) { hist_.emplace(key, h); }

 private:
  std::vector<std::int32_t> entity_, mesh_of_, cand_start_, cands_, coefficient_;
  HistoryMap hist_, hist_next_;
  std::vector<std::vector<Vec3>> nodes_at_find_;
};

}  // namespace tessera
