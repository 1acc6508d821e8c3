// SPDX-License-Identifier: MIT
// The DEM's free-sphere stage (T17, free_spheres.hpp): the free spheres themselves (held alike on
// every rank), their contacts with the owned entities (contact_entities.hpp; the body-body law, m*
// and R* of the grain and the sphere) and with the wall planes and mesh walls (the wall law, the
// sphere's mass and radius; computed on every rank alike). It owns the (entity, sphere) pairs within
// reach at the last search, the coefficient sets, and two kinds of springs: grain-sphere ones keyed
// by (element key, sphere) (contact_history.hpp free_sphere_key), which travel with their grains,
// and the spheres' own wall and mesh springs (the same on every rank).
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "solid/contact_entities.hpp"
#include "solid/contact_history.hpp"
#include "solid/free_spheres.hpp"
#include "solid/replicated_loads.hpp"
#include "solid/walls.hpp"

namespace tessera {

class FreeSphereContacts {
 public:
  void add(const FreeSphere& s);  // every rank alike, before set-up
  std::vector<FreeSphere>& spheres() { return spheres_; }
  const std::vector<FreeSphere>& spheres() const { return spheres_; }
  bool empty() const { return spheres_.empty(); }

  // The owned entities within reach (radius + radius + skin) of each sphere; the spheres' centres
  // at this search.
  void find(const ContactEntities& entities, double skin);
  double displacement() const;  // the largest since the last find
  // Coefficient sets: with grains as a body pair (m*, R* of the two), with walls and meshes as a
  // wall (the sphere's m and R). lookup(material a, material b, m*, R*) -> index.
  template <class Lookup>
  // The spheres' coefficient sets with the walls and meshes (grains take the body-body law's
  // coefficients in the kernel, from their material pair and m*).
  void fill_coefficients(const Walls& walls, Lookup&& lookup) {
    wall_coefficient_.clear();
    for (const auto& s : spheres_) {
      for (const auto& w : walls.primitives()) wall_coefficient_.push_back(lookup(s.material, w.material, s.mass, s.radius));
      for (const auto& m : walls.meshes()) wall_coefficient_.push_back(lookup(s.material, m.material, s.mass, s.radius));
    }
  }
  // The owned entities' contacts with the spheres into the entities' contact buffer; their
  // reactions listed in `loads` (target: mesh_count + sphere). The spheres' force and torque are
  // reset; the springs advanced by dt (dt = 0: unchanged).
  void grain_forces(ContactEntities& entities, ContactLanes& lanes, const ContactModel& model, double dt,
                    std::size_t mesh_count, ReplicatedLoads& loads);
  // Every rank alike: each sphere against the wall planes and the meshes, added to the spheres'
  // and the meshes' loads.
  void wall_forces(Walls& walls, ContactLanes& lanes, const ContactCoefficients* sets, LawKind law, double dt);

  // Grain-sphere springs: all (restart, migration), and the ones that came with arriving grains.
  const HistoryMap& grain_springs() const { return grain_hist_; }
  void adopt(PairKey key, const std::array<double, 3>& h) { grain_hist_.emplace(key, h); }
  // The spheres' wall and mesh springs (restart).
  const HistoryMap& wall_springs() const { return wall_hist_; }
  void set_wall_springs(HistoryMap h) { wall_hist_ = std::move(h); }

 private:
  std::vector<FreeSphere> spheres_;
  std::vector<std::int32_t> entity_, sphere_of_, wall_coefficient_;  // walls: sphere-major
  HistoryMap grain_hist_, grain_hist_next_, wall_hist_, wall_hist_next_;
  struct Touch {  // a sphere's contact with a wall plane (mesh -1) or a mesh
    PairKey key;
    Vec3 normal, point;
    double overlap;
    int coefficient, mesh;
  };
  std::vector<Touch> touches_;                  // reused each step
  std::vector<std::vector<int>> triangle_ids_;  // per mesh: 0 .. triangles - 1
};

}  // namespace tessera
