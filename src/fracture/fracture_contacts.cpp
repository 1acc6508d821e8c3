// SPDX-License-Identifier: MIT
// Contact spheres and their list (docs/theory.md B6-B7): spheres on the block's surface and on
// released faces, the Verlet list of sphere pairs of different, unbonded elements (an element that
// has moved more than skin/2 minus what the coming step may add is searched again, a full build
// when a quarter of them have; new spheres added to the list as faces break), and the pair's force.
#include <algorithm>
#include <cmath>

#include "fracture/fracture_solver.hpp"

namespace tessera {

void FractureSolver::add_spheres(int bond) {
  const BondGeometry& g = block_.bonds[static_cast<std::size_t>(bond)];
  const int d = settings_.sphere_divisions;
  long key = static_cast<long>(bond) * (d - 1) * (d - 2);  // (bond, side, k): the canonical order
  for (const auto& [e, f] : {std::pair{g.master, g.master_face}, std::pair{g.slave, g.slave_face}})
    for (const FaceSphere& s : face_spheres(block_.vertices[static_cast<std::size_t>(e)], f, settings_.sphere_divisions)) {
      element_spheres_[static_cast<std::size_t>(e)].push_back(static_cast<int>(spheres_.size()));
      spheres_.push_back({e, s.centre, s.radius, key++});
      max_radius_ = std::max(max_radius_, s.radius);
    }
  unlisted_bonds_.push_back(bond);
}

void FractureSolver::add_surface_spheres() {
  // B6: the block's own surface (the hole's wall included) carries spheres from the start, so that
  // fragments meet it; their keys follow every bond's.
  const int d = settings_.sphere_divisions;
  const long ns = (d - 1) * (d - 2) / 2;
  for (std::size_t f = 0; f < block_.surface.size(); ++f) {
    const SurfaceFace& sf = block_.surface[f];
    long key = (2 * static_cast<long>(block_.bonds.size()) + static_cast<long>(f)) * ns;
    for (const FaceSphere& s : face_spheres(block_.vertices[static_cast<std::size_t>(sf.element)], sf.face, d)) {
      element_spheres_[static_cast<std::size_t>(sf.element)].push_back(static_cast<int>(spheres_.size()));
      spheres_.push_back({sf.element, s.centre, s.radius, key++});
      max_radius_ = std::max(max_radius_, s.radius);
    }
  }
}

bool FractureSolver::bonded(int a, int b) const {
  for (int k : element_bonds_[static_cast<std::size_t>(a)]) {
    const BondGeometry& g = block_.bonds[static_cast<std::size_t>(k)];
    if ((g.master == b || g.slave == b) && !broken_[static_cast<std::size_t>(k)]) return true;
  }
  return false;
}

int FractureSolver::mark_stale(double horizon) {
  // B6's list check, per element: a point at distance r from its centroid moved at most
  // |dx| + theta r since the element was last searched (theta: the rotation between the two
  // orientations); with what the coming step may add, it must stay within skin/2. What it may add:
  // twice the fastest of its own speed and its listed partners' (a contact cannot throw it faster),
  // over `horizon` (the macro step; 0 for the uniform step, checked every step).
  const std::size_t n = block_.size();
  moved_.assign(n, 0.0);
  stale_.assign(n, 0);
  for (std::size_t e = 0; e < n; ++e) {
    const Quaternion& a = q_[e];
    const Quaternion& b = build_q_[e];
    const double c = std::min(1.0, std::fabs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z));
    moved_[e] = norm(x_[e] - build_x_[e]) + 2 * std::acos(c) * reach_[e];
  }
  if (horizon > 0) {
    // Each element's bound from its owner (which lists all its pairs), then every rank alike.
    std::vector<double>& speed = scratch_speed_;
    speed.resize(n);
    for (std::size_t e = 0; e < n; ++e) speed[e] = norm(v_[e]) + norm(w_[e]) * reach_[e];
    std::vector<double>& fastest = scratch_fastest_;
    fastest.assign(speed.begin(), speed.end());
    for (const ListedPair& lp : pairs_) {
      const std::size_t a = static_cast<std::size_t>(lp.ea), b = static_cast<std::size_t>(lp.eb);
      fastest[a] = std::max(fastest[a], speed[b]), fastest[b] = std::max(fastest[b], speed[a]);
    }
    const int rank = decomp_.rank();
    for (std::size_t e = 0; e < n; ++e)
      stale_[e] = owner_[e] == rank && moved_[e] + 2 * fastest[e] * horizon > 0.5 * skin_;
    if (decomp_.size() > 1)
      MPI_Allreduce(MPI_IN_PLACE, stale_.data(), static_cast<int>(n), MPI_CHAR, MPI_MAX, decomp_.comm());
  } else {
    for (std::size_t e = 0; e < n; ++e) stale_[e] = moved_[e] > 0.5 * skin_;
  }
  return static_cast<int>(std::count(stale_.begin(), stale_.end(), 1));
}

void FractureSolver::reset_grid() {
  double smallest = cell_radius_;
  for (const Sphere& sp : spheres_) smallest = std::min(smallest, sp.radius);
  for (SphereGrid& g : grids_) g.reset(1.5 * cell_radius_, smallest, 2 * skin_);
}

Vec3 FractureSolver::sphere_position(std::size_t s) const {
  const std::size_t e = static_cast<std::size_t>(spheres_[s].element);
  return x_[e] + q_[e].rotate(spheres_[s].centre);
}

void FractureSolver::consider_pair(int a, int b, const Vec3& pa, const Vec3& pb, double margin, bool born) {
  const Sphere &sa = spheres_[static_cast<std::size_t>(a)], &sb = spheres_[static_cast<std::size_t>(b)];
  // The cheap tests first: most candidates are out of reach.
  const double reach = sa.radius + sb.radius + skin_ + margin;
  const double d2 = norm2(pa - pb);
  if (d2 >= reach * reach || sa.element == sb.element) return;
  const int rank = decomp_.rank();
  const bool own_a = owner_[static_cast<std::size_t>(sa.element)] == rank;
  if (!own_a && owner_[static_cast<std::size_t>(sb.element)] != rank) return;
  if (bonded(sa.element, sb.element)) return;
  ListedPair p = sa.key < sb.key ? listed_pair(a, b) : listed_pair(b, a);
  if (sunk_.empty() && !born) return pairs_.push_back(p);  // most listings: no depth to find
  const double overlap = sa.radius + sb.radius - std::sqrt(d2);
  if (!sunk_.empty()) {
    // Listed again: the depth it kept, at most its overlap now (none once open), as an evaluation would.
    const auto it = sunk_.find({std::min(sa.key, sb.key), std::max(sa.key, sb.key)});
    if (it != sunk_.end()) set_sunk(p, std::clamp(overlap, 0.0, it->second));
  }
  if (overlap > 0 && born && settings_.relax_born_overlaps && p.sunk == 0 && born_at_release(a, b)) {
    // B7b: born overlapping at a release; the pair's force starts from here.
    set_sunk(p, overlap);
    if (own_a) ++born_overlaps_, deepest_born_ = std::max(deepest_born_, overlap);
  }
  pairs_.push_back(p);
}

bool FractureSolver::born_at_release(int a, int b) const {
  if (static_cast<std::size_t>(a) >= listed_spheres_ || static_cast<std::size_t>(b) >= listed_spheres_) return true;
  const int ea = spheres_[static_cast<std::size_t>(a)].element, eb = spheres_[static_cast<std::size_t>(b)].element;
  for (int bond : unlisted_bonds_) {
    const BondGeometry& g = block_.bonds[static_cast<std::size_t>(bond)];
    if ((g.master == ea && g.slave == eb) || (g.master == eb && g.slave == ea)) return true;
  }
  return false;
}

void FractureSolver::set_sunk(ListedPair& p, double depth) {
  // Every rank that lists the pair evaluates it at the same states, so every copy agrees.
  p.sunk = depth;
  const long ka = spheres_[static_cast<std::size_t>(p.first)].key, kb = spheres_[static_cast<std::size_t>(p.second)].key;
  if (depth > 0)
    sunk_[{ka, kb}] = depth;
  else
    sunk_.erase({ka, kb});
}

void FractureSolver::keep_sunk() {
  // Before the list changes: the pairs that opened leave the map, the others with a depth set it.
  for (const std::size_t k : opened_)
    sunk_.erase({spheres_[static_cast<std::size_t>(pairs_[k].first)].key, spheres_[static_cast<std::size_t>(pairs_[k].second)].key});
  opened_.clear();
  for (const ListedPair& p : pairs_)
    if (p.sunk > 0) sunk_[{spheres_[static_cast<std::size_t>(p.first)].key, spheres_[static_cast<std::size_t>(p.second)].key}] = p.sunk;
}

std::map<std::pair<long, long>, double> FractureSolver::current_sunk() const {
  // The map as keep_sunk would leave it now.
  std::map<std::pair<long, long>, double> m = sunk_;
  for (const ListedPair& p : pairs_) {
    const std::pair<long, long> key{spheres_[static_cast<std::size_t>(p.first)].key, spheres_[static_cast<std::size_t>(p.second)].key};
    if (p.sunk > 0)
      m[key] = p.sunk;
    else
      m.erase(key);
  }
  return m;
}

void FractureSolver::sort_pairs(std::size_t sorted) {
  // Canonical order (sphere keys), whatever order the faces broke in or a restart re-created them.
  // The first `sorted` pairs are in that order already (those a refresh kept): the rest are sorted
  // and merged in.
  const auto by_keys = [&](const auto& p, const auto& r) {
    const auto& S = spheres_;
    return std::pair{S[static_cast<std::size_t>(p.first)].key, S[static_cast<std::size_t>(p.second)].key} <
           std::pair{S[static_cast<std::size_t>(r.first)].key, S[static_cast<std::size_t>(r.second)].key};
  };
  const auto mid = pairs_.begin() + static_cast<std::ptrdiff_t>(std::min(sorted, pairs_.size()));
  std::sort(mid, pairs_.end(), by_keys);
  std::inplace_merge(pairs_.begin(), mid, pairs_.end(), by_keys);
}

void FractureSolver::build_list() {
  ++list_builds_;
  pairs_.clear();
  build_x_ = x_, build_q_ = q_;
  const std::size_t n = spheres_.size();
  std::vector<Vec3>& at = scratch_at_;
  at.resize(n);
  for (std::size_t s = 0; s < n; ++s) at[s] = sphere_position(s);
  cell_radius_ = max_radius_;
  reset_grid();
  for (std::size_t s = 0; s < n; ++s) insert_sphere(s, at[s]);
  for (std::size_t a = 0; a < n; ++a) {
    // Each pair once: from its smaller sphere, and within one size class from the lower index.
    const Vec3& p = at[a];
    const int ia = static_cast<int>(a);
    const double r = spheres_[a].radius;
    const int cls = grids_[0].size_class(r);
    near_sphere(a, p, true, [&](int b) {
      if (b == ia || (b < ia && grids_[0].size_class(spheres_[static_cast<std::size_t>(b)].radius) == cls)) return;
      consider_pair(std::min(ia, b), std::max(ia, b), at[static_cast<std::size_t>(std::min(ia, b))],
                    at[static_cast<std::size_t>(std::max(ia, b))], 0, true);
    });
  }
  unlisted_bonds_.clear();
  listed_spheres_ = n;
  sort_pairs();
  count_pairs();
}

void FractureSolver::extend_list() {
  // Faces released since the list was made: their new spheres against every sphere within reach
  // now (the grid holds each sphere where its element was last searched, within skin/2 of where it
  // is: the grid's pad covers it), and the two elements' older spheres against each other.
  // Safe until the next rebuild: from now on each element moves at most skin/2 - what it has moved.
  const std::size_t n = spheres_.size(), sorted = pairs_.size();
  for (std::size_t a = listed_spheres_; a < n; ++a) {
    const Vec3 p = sphere_position(a);
    near_sphere(a, p, false, [&](int b) { consider_pair(static_cast<int>(a), b, p, sphere_position(static_cast<std::size_t>(b)), 0, true); });
    const std::size_t e = static_cast<std::size_t>(spheres_[a].element);
    insert_sphere(a, build_x_[e] + build_q_[e].rotate(spheres_[a].centre));  // where its element was searched
  }
  for (int bond : unlisted_bonds_) {
    const BondGeometry& g = block_.bonds[static_cast<std::size_t>(bond)];
    for (int a : element_spheres_[static_cast<std::size_t>(g.master)]) {
      if (static_cast<std::size_t>(a) >= listed_spheres_) continue;
      const Vec3 pa = sphere_position(static_cast<std::size_t>(a));
      for (int b : element_spheres_[static_cast<std::size_t>(g.slave)])
        if (static_cast<std::size_t>(b) < listed_spheres_) consider_pair(a, b, pa, sphere_position(static_cast<std::size_t>(b)), 0, true);
    }
  }
  // A pair of two elements whose bond broke is listed once: two older bonds between the same two
  // elements cannot exist (they share one face).
  unlisted_bonds_.clear();
  listed_spheres_ = n;
  sort_pairs(sorted);
  count_pairs();
}

void FractureSolver::count_pairs() {
  // Collective. Each element's listed pairs, from its owner (which lists all of them).
  listed_pairs_.assign(block_.size(), 0);
  const int rank = decomp_.rank();
  for (const ListedPair& lp : pairs_)
    for (const int s : {lp.first, lp.second}) {
      const std::size_t e = static_cast<std::size_t>(spheres_[static_cast<std::size_t>(s)].element);
      if (owner_[e] == rank) ++listed_pairs_[e];
    }
  if (decomp_.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, listed_pairs_.data(), static_cast<int>(listed_pairs_.size()), MPI_INT, MPI_MAX,
                  decomp_.comm());
}

void FractureSolver::refresh_list() {
  // The elements that moved too far (stale_) searched again where they are now; every other
  // element keeps its pairs. A pair of a searched element A with an element X that has moved m_X
  // since its own search is listed within reach + m_X: from now on A moves at most skin/2 and X at
  // most skin/2 + m_X from here, so a pair not listed stays apart until one of them is stale.
  ++list_refreshes_;
  std::erase_if(pairs_, [&](const ListedPair& p) {
    return stale_[static_cast<std::size_t>(p.ea)] || stale_[static_cast<std::size_t>(p.eb)];
  });
  const std::size_t sorted = pairs_.size();
  // The grid holds every sphere where its element was last searched (within skin/2 of where it is
  // now, 2 skins of pad with the margin below): the searched elements' spheres move to where they are.
  for (std::size_t e = 0; e < block_.size(); ++e) {
    if (!stale_[e]) continue;
    build_x_[e] = x_[e], build_q_[e] = q_[e];
    for (const int a : element_spheres_[e])
      grid_of(static_cast<std::size_t>(a)).move(a, sphere_position(static_cast<std::size_t>(a)), spheres_[static_cast<std::size_t>(a)].radius);
  }
  for (std::size_t e = 0; e < block_.size(); ++e) {
    if (!stale_[e]) continue;
    for (const int a : element_spheres_[e]) {
      const Vec3 p = sphere_position(static_cast<std::size_t>(a));
      near_sphere(static_cast<std::size_t>(a), p, false, [&](int b) {
        const std::size_t eb = static_cast<std::size_t>(spheres_[static_cast<std::size_t>(b)].element);
        if (stale_[eb] && (eb < e || (eb == e && b <= a))) return;  // two searched elements: once
        consider_pair(a, b, p, sphere_position(static_cast<std::size_t>(b)), stale_[eb] ? 0.0 : moved_[eb]);
      });
    }
  }
  sort_pairs(sorted);
  count_pairs();
}

void FractureSolver::update_list(double horizon) {
  keep_sunk();
  // Never built, spheres larger than the cells allow, or most elements stale: a full build.
  if (build_x_.empty() || max_radius_ > 1.5 * cell_radius_) return build_list();  // the grid's r_top
  if (listed_spheres_ < spheres_.size()) extend_list();
  const int stale = mark_stale(horizon);
  if (stale == 0) return;
  if (4 * static_cast<std::size_t>(stale) > block_.size()) return build_list();
  refresh_list();
}

PairForce FractureSolver::contact_force(std::size_t pair, const Pose& pa, const Pose& pb, double h) {
  const int a = pairs_[pair].first, b = pairs_[pair].second;
  const Sphere &sa = spheres_[static_cast<std::size_t>(a)], &sb = spheres_[static_cast<std::size_t>(b)];
  const std::size_t ea = static_cast<std::size_t>(sa.element), eb = static_cast<std::size_t>(sb.element);
  PairForce out;
  const Vec3 ca = pa.x + pa.rot(sa.centre), cb = pb.x + pb.rot(sb.centre);
  const Vec3 d = ca - cb;
  const double dist = norm(d), overlap = sa.radius + sb.radius - dist;
  out.gap = -overlap;
  // B7b: a pair born overlapping pushes only beyond its sunk depth, which follows it as it opens.
  ListedPair& lp = pairs_[pair];
  if (lp.sunk > 0 && overlap < lp.sunk) {  // the map follows at keep_sunk
    lp.sunk = std::max(0.0, overlap);
    if (lp.sunk == 0) opened_.push_back(pair);
  }
  const double depth = overlap - lp.sunk;
  if (depth <= 0 || dist == 0) return out;
  const double k = settings_.contact_stiffness, c = settings_.damping ? settings_.contact_damping : 0;
  const Vec3 n = d / dist;
  const Vec3 cp = cb + n * (sb.radius - 0.5 * overlap);
  const Vec3 arm_a = cp - pa.x, arm_b = cp - pb.x;
  const Vec3 vrel = (pa.v + cross(pa.w, arm_a)) - (pb.v + cross(pb.w, arm_b));
  const double vn = dot(vrel, n);
  // B7: the dashpot and the friction, each as backward Euler on the pair over its step h with the
  // pair's mobility along the direction (translation and rotation of both elements), each element's
  // share split between its listed pairs (Jacobi): c / (1 + c h w) tends to c as h -> 0, and the
  // pairs of an element together cannot reverse a relative velocity within a step (Table 1's dashpot
  // is ~200 times critical: explicit, it needs h < 2 m / c, 1e-8 s for a 5 cm element).
  const auto mobility = [&](const Vec3& dir) {
    const auto side = [&](const Pose& p, std::size_t e, const Vec3& arm) {
      const Vec3 t = p.unrot(cross(arm, dir));
      const Vec3& I = block_.inertia[e];
      return static_cast<double>(listed_pairs_[e]) * (1 / block_.mass[e] + t.x * t.x / I.x + t.y * t.y / I.y + t.z * t.z / I.z);
    };
    return side(pa, ea, arm_a) + side(pb, eb, arm_b);
  };
  const double c_eff = c / (1 + c * h * mobility(n));
  const double fn = std::max(0.0, k * depth - c_eff * vn);
  Vec3 F = n * fn;
  const Vec3 vt = vrel - n * vn;
  const double st = norm(vt);
  if (st > 0) F -= vt * (std::min(settings_.contact_friction * fn, st / (h * mobility(vt / st))) / st);
  out.force = F;  // on a; -F on b
  out.torque_j = cross(arm_a, F);
  out.torque_i = -cross(arm_b, F);
  return out;
}

void FractureSolver::contact_forces() {
  if (spheres_.empty()) return;
  const int rank = decomp_.rank();
  for (std::size_t p = 0; p < pairs_.size(); ++p) {
    const std::size_t ea = static_cast<std::size_t>(pairs_[p].ea), eb = static_cast<std::size_t>(pairs_[p].eb);
    if (settings_.skip_apart && !may_touch(pairs_[p], ea, eb)) continue;  // B7a
    ++contact_evaluations_;
    const PairForce f = contact_force(p, pose(ea), pose(eb), dt_);
    if (settings_.skip_apart) note_gap(pairs_[p], ea, eb, f.gap);
    if (owner_[ea] == rank) F_[ea] += f.force, T_[ea] += f.torque_j;
    if (owner_[eb] == rank) F_[eb] -= f.force, T_[eb] += f.torque_i;
  }
}

}  // namespace tessera
