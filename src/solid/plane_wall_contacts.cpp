// SPDX-License-Identifier: MIT
#include "solid/plane_wall_contacts.hpp"

namespace tessera {

namespace {

// Shaped mode: can an element of element e's body come within its radius + skin of a wall? Its
// centre is within element_reach - r of the body's, and a wall's overlap is the radius less a
// distance that changes at most as fast as the point moves, so a body farther than element_reach
// + skin from every wall has no entry (one skin more as a margin for round-off). Asked once a body
// (the cache holds the last body's answer); sphere bodies always answer yes.
struct NearWalls {
  const ContactEntities& entities;
  const std::vector<WallPrimitive>& prims;
  double skin;
  std::size_t body = static_cast<std::size_t>(-1);
  bool near = true;
  bool operator()(std::size_t e) {
    if (!entities.shaped()) return true;
    const std::size_t i = entities.body(e);
    if (i == body) return near;
    body = i;
    near = false;
    const Vec3 x = entities.bodies().pos(i);
    const double reach = entities.element_reach(i) + 2.0 * skin;
    for (const auto& w : prims) {
      Vec3 n;
      if (w.overlap(x, reach, n) > 0.0) return near = true;
    }
    return near;
  }
};

}  // namespace

void PlaneWallContacts::find(const ContactEntities& entities, const Walls& walls, double skin,
                             const HistoryMap& extra) {
  old_keys_.swap(keys_), old_hist_.swap(hist_);
  keys_.clear(), hist_.clear(), entity_.clear(), slot_.clear();
  const auto& old_keys = old_keys_;
  const auto& old_hist = old_hist_;
  const auto& prims = walls.primitives();
  const bool sh = entities.shaped();
  std::size_t old = 0;
  NearWalls near{entities, prims, skin};
  for (std::size_t e = 0; e < entities.owned(); ++e) {
    if (!near(e)) continue;
    const Vec3 xe = entities.centre(e);
    for (std::size_t s = 0; s < prims.size(); ++s) {
      Vec3 n;
      if (prims[s].overlap(xe, entities.radius(e) + skin, n) <= 0.0) continue;
      entity_.push_back(static_cast<std::int32_t>(e));
      slot_.push_back(static_cast<std::int32_t>(s));
      if (!sh) continue;  // sphere bodies: the spring is in the body's wall_history
      const PairKey key = wall_key(entities.key(e), static_cast<int>(s));
      keys_.push_back(key);
      std::array<double, 3> h{0, 0, 0};
      while (old < old_keys.size() && old_keys[old] < key) ++old;
      if (old < old_keys.size() && old_keys[old] == key) {
        h = {old_hist[3 * old], old_hist[3 * old + 1], old_hist[3 * old + 2]};
      } else if (const auto it = extra.find(key); it != extra.end()) {
        h = it->second;
      }
      hist_.insert(hist_.end(), h.begin(), h.end());
    }
  }
}

void PlaneWallContacts::refind(const ContactEntities& entities, const Walls& walls, double skin,
                               const std::vector<char>& stale_body) {
  old_entity_.swap(entity_), old_slot_.swap(slot_), old_keys_.swap(keys_), old_hist_.swap(hist_);
  entity_.clear(), slot_.clear(), keys_.clear(), hist_.clear();
  const auto& old_entity = old_entity_;
  const auto& old_slot = old_slot_;
  const auto& old_keys = old_keys_;
  const auto& old_hist = old_hist_;
  const auto& prims = walls.primitives();
  std::size_t o = 0;
  NearWalls near{entities, prims, skin};
  for (std::size_t e = 0; e < entities.owned(); ++e) {
    if (!stale_body[entities.body(e)]) {
      for (; o < old_entity.size() && static_cast<std::size_t>(old_entity[o]) == e; ++o) {
        entity_.push_back(old_entity[o]), slot_.push_back(old_slot[o]), keys_.push_back(old_keys[o]);
        hist_.insert(hist_.end(), &old_hist[3 * o], &old_hist[3 * o + 3]);
      }
      continue;
    }
    if (!near(e)) {  // no entry now: its old ones go
      while (o < old_entity.size() && static_cast<std::size_t>(old_entity[o]) == e) ++o;
      continue;
    }
    const Vec3 xe = entities.centre(e);
    for (std::size_t s = 0; s < prims.size(); ++s) {
      Vec3 n;
      if (prims[s].overlap(xe, entities.radius(e) + skin, n) <= 0.0) continue;
      const PairKey key = wall_key(entities.key(e), static_cast<int>(s));
      entity_.push_back(static_cast<std::int32_t>(e)), slot_.push_back(static_cast<std::int32_t>(s)), keys_.push_back(key);
      std::array<double, 3> h{0, 0, 0};
      while (o < old_entity.size() && (static_cast<std::size_t>(old_entity[o]) < e ||
                                       (static_cast<std::size_t>(old_entity[o]) == e && old_keys[o] < key)))
        ++o;
      if (o < old_entity.size() && old_keys[o] == key) h = {old_hist[3 * o], old_hist[3 * o + 1], old_hist[3 * o + 2]};
      hist_.insert(hist_.end(), h.begin(), h.end());
    }
    while (o < old_entity.size() && static_cast<std::size_t>(old_entity[o]) == e) ++o;
  }
}

void PlaneWallContacts::forces(ContactEntities& entities, ParticleStore& bodies, const Walls& walls,
                               ContactLanes& L, const ContactCoefficients* sets, LawKind law, double dt) {
  // Entries in (entity, wall) order; entities read as the kernel mirrors packed this step.
  const bool sh = entities.shaped();
  const auto& prims = walls.primitives();
  const std::size_t slots = static_cast<std::size_t>(walls.slots());
  entry_force_.resize(3 * entity_.size());  // every entry is written below
  std::int32_t lane_entry[ContactLanes::width];
  auto spring = [&](std::size_t k) {
    return sh ? &hist_[3 * k] : &bodies.wall_history[3 * (entity_[k] * slots + slot_[k])];
  };
  std::size_t nb = 0;
  auto flush = [&] {
    evaluate_wall_contacts(law, L, nb, dt);
    for (std::size_t j = 0; j < nb; ++j) {
      const std::size_t k = static_cast<std::size_t>(lane_entry[j]);
      double* h = spring(k);
      h[0] = L.hx[j], h[1] = L.hy[j], h[2] = L.hz[j];
      entities.add_wall_reaction(entity_[k], L, j);
      double* load = &entry_force_[3 * k];
      load[0] = -L.fx[j], load[1] = -L.fy[j], load[2] = -L.fz[j];
    }
    nb = 0;
  };
  for (std::size_t k = 0; k < entity_.size(); ++k) {
    const std::size_t i = entity_[k];
    double* h = spring(k);
    Vec3 nrm;
    const KernelGeometry gi = entities.geometry(i);
    const double ri = gi.r;
    const double delta = prims[slot_[k]].overlap(Vec3{gi.x, gi.y, gi.z}, ri, nrm);
    if (delta <= 0.0) {
      h[0] = h[1] = h[2] = 0.0;
      double* load = &entry_force_[3 * k];
      load[0] = load[1] = load[2] = 0.0;
      continue;
    }
    if (sh) entities.refresh_motion(i);
    const KernelMotion mi = entities.motion(i);
    L.dx[nb] = nrm.x, L.dy[nb] = nrm.y, L.dz[nb] = nrm.z;
    L.ra[nb] = ri, L.rb[nb] = delta;
    L.vx[nb] = mi.vx, L.vy[nb] = mi.vy, L.vz[nb] = mi.vz;
    L.wx[nb] = mi.wx * ri, L.wy[nb] = mi.wy * ri, L.wz[nb] = mi.wz * ri;
    L.hx[nb] = h[0], L.hy[nb] = h[1], L.hz[nb] = h[2];
    L.set_coefficients(nb, sets[coefficient_[k]]);
    lane_entry[nb++] = static_cast<std::int32_t>(k);
    if (nb == ContactLanes::width) flush();
  }
  if (nb) flush();
}

std::vector<Vec3> PlaneWallContacts::loads(const Walls& walls, MPI_Comm comm) const {
  // Exact sums over every contact (core/exact_sum.hpp): a floor's load is the same bits on any
  // rank count, however the bodies touching it are spread over the ranks.
  const std::size_t slots = static_cast<std::size_t>(walls.slots());
  std::vector<ExactSum> sums(3 * slots);
  for (std::size_t k = 0; k < slot_.size() && 3 * k < entry_force_.size(); ++k)
    for (int d = 0; d < 3; ++d) sums[3 * static_cast<std::size_t>(slot_[k]) + d] += entry_force_[3 * k + d];
  ExactSum::all_reduce(sums, comm);
  std::vector<Vec3> f(slots);
  for (std::size_t s = 0; s < slots; ++s) f[s] = {sums[3 * s].value(), sums[3 * s + 1].value(), sums[3 * s + 2].value()};
  return f;
}

void PlaneWallContacts::track_impulse(bool on) {
  track_impulse_ = on;
  impulse_ = {};
}

void PlaneWallContacts::add_half_impulse(double dt) {
  for (std::size_t k = 0; 3 * k + 2 < entry_force_.size(); ++k)
    for (int d = 0; d < 3; ++d) impulse_[d] += -0.5 * dt * entry_force_[3 * k + d];
}

Vec3 PlaneWallContacts::impulse(MPI_Comm comm) const {
  std::array<ExactSum, 3> sums = impulse_;
  ExactSum::all_reduce(sums, comm);
  return {sums[0].value(), sums[1].value(), sums[2].value()};
}

void PlaneWallContacts::collect(HistoryMap& h) const {
  for (std::size_t k = 0; k < keys_.size(); ++k) {
    const double* w = &hist_[3 * k];
    if (w[0] != 0.0 || w[1] != 0.0 || w[2] != 0.0) h[keys_[k]] = {w[0], w[1], w[2]};
  }
}

void PlaneWallContacts::collect_leaving(const ContactEntities& entities, const std::vector<char>& leaving,
                                        HistoryMap& h) const {
  for (std::size_t k = 0; k < keys_.size(); ++k) {
    const double* w = &hist_[3 * k];
    if (leaving[entities.body(entity_[k])] && (w[0] != 0.0 || w[1] != 0.0 || w[2] != 0.0))
      h[keys_[k]] = {w[0], w[1], w[2]};
  }
}

}  // namespace tessera
