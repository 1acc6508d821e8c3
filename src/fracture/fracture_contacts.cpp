// SPDX-License-Identifier: MIT
// Contact spheres and their list (docs/theory.md B6-B7): spheres on the block's surface and on
// released faces, the Verlet list of sphere pairs of different, unbonded elements (full builds
// when an element has moved more than skin/2 minus what the coming step may add; new spheres
// added to the list as faces break), and the pair's force.
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

bool FractureSolver::list_stale(double ahead) const {
  if (build_x_.empty() || max_radius_ > 1.5 * cell_radius_) return true;  // never built; cells too small
  const double limit = 0.5 * skin_ - ahead;
  if (limit <= 0) return true;
  // Per element: a point at distance r from its centroid moved at most |dx| + theta r since the
  // build, theta the rotation angle between the two orientations.
  for (std::size_t e = 0; e < block_.size(); ++e) {
    const Quaternion& a = q_[e];
    const Quaternion& b = build_q_[e];
    const double c = std::min(1.0, std::fabs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z));
    if (norm(x_[e] - build_x_[e]) + 2 * std::acos(c) * reach_[e] > limit) return true;
  }
  return false;
}

long FractureSolver::cell_key(const Vec3& p) const {
  auto c = [&](double v) { return (static_cast<long>(std::floor(v / cell_size_)) + (1L << 20)) & 0x1FFFFF; };
  return c(p.x) | (c(p.y) << 21) | (c(p.z) << 42);
}

Vec3 FractureSolver::sphere_position(std::size_t s) const {
  const std::size_t e = static_cast<std::size_t>(spheres_[s].element);
  return x_[e] + q_[e].rotate(spheres_[s].centre);
}

void FractureSolver::consider_pair(int a, int b, const Vec3& pa, const Vec3& pb) {
  const Sphere &sa = spheres_[static_cast<std::size_t>(a)], &sb = spheres_[static_cast<std::size_t>(b)];
  if (sa.element == sb.element || bonded(sa.element, sb.element)) return;
  const int rank = decomp_.rank();
  if (owner_[static_cast<std::size_t>(sa.element)] != rank && owner_[static_cast<std::size_t>(sb.element)] != rank) return;
  const double reach = sa.radius + sb.radius + skin_;
  if (norm2(pa - pb) >= reach * reach) return;
  pairs_.push_back(sa.key < sb.key ? std::pair{a, b} : std::pair{b, a});
}

void FractureSolver::sort_pairs() {
  // Canonical order (sphere keys), whatever order the faces broke in or a restart re-created them.
  std::sort(pairs_.begin(), pairs_.end(), [&](const auto& p, const auto& r) {
    const auto& S = spheres_;
    return std::pair{S[static_cast<std::size_t>(p.first)].key, S[static_cast<std::size_t>(p.second)].key} <
           std::pair{S[static_cast<std::size_t>(r.first)].key, S[static_cast<std::size_t>(r.second)].key};
  });
}

void FractureSolver::build_list() {
  ++list_builds_;
  pairs_.clear();
  unlisted_bonds_.clear();
  listed_spheres_ = spheres_.size();
  build_x_ = x_, build_q_ = q_;
  const std::size_t n = spheres_.size();
  std::vector<Vec3> at(n);
  for (std::size_t s = 0; s < n; ++s) at[s] = sphere_position(s);
  cell_radius_ = max_radius_;
  cell_size_ = 2 * max_radius_ + skin_;
  cells_.clear();
  for (std::size_t s = 0; s < n; ++s) cells_[cell_key(at[s])].push_back(static_cast<int>(s));
  for (std::size_t a = 0; a < n; ++a) {
    const Vec3& p = at[a];
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(cell_key(p + Vec3{dx * cell_size_, dy * cell_size_, dz * cell_size_}));
          if (it == cells_.end()) continue;
          for (int b : it->second)
            if (b > static_cast<int>(a)) consider_pair(static_cast<int>(a), b, p, at[static_cast<std::size_t>(b)]);
        }
  }
  sort_pairs();
  count_pairs();
}

void FractureSolver::extend_list() {
  // Faces released since the list was made: their new spheres against every sphere within reach
  // now (the cells hold each sphere within skin/2 of where it is, so two cells around cover
  // reach + skin/2), and the two elements' older spheres against each other (no longer bonded).
  // Safe until the next rebuild: from now on each element moves at most skin/2 - what it has moved.
  const std::size_t n = spheres_.size();
  for (std::size_t a = listed_spheres_; a < n; ++a) {
    const Vec3 p = sphere_position(a);
    for (long dx = -2; dx <= 2; ++dx)
      for (long dy = -2; dy <= 2; ++dy)
        for (long dz = -2; dz <= 2; ++dz) {
          const auto it = cells_.find(cell_key(p + Vec3{dx * cell_size_, dy * cell_size_, dz * cell_size_}));
          if (it == cells_.end()) continue;
          for (int b : it->second) consider_pair(static_cast<int>(a), b, p, sphere_position(static_cast<std::size_t>(b)));
        }
    cells_[cell_key(p)].push_back(static_cast<int>(a));
  }
  for (int bond : unlisted_bonds_) {
    const BondGeometry& g = block_.bonds[static_cast<std::size_t>(bond)];
    for (int a : element_spheres_[static_cast<std::size_t>(g.master)]) {
      if (static_cast<std::size_t>(a) >= listed_spheres_) continue;
      const Vec3 pa = sphere_position(static_cast<std::size_t>(a));
      for (int b : element_spheres_[static_cast<std::size_t>(g.slave)])
        if (static_cast<std::size_t>(b) < listed_spheres_) consider_pair(a, b, pa, sphere_position(static_cast<std::size_t>(b)));
    }
  }
  // A pair of two elements whose bond broke is listed once: two older bonds between the same two
  // elements cannot exist (they share one face).
  unlisted_bonds_.clear();
  listed_spheres_ = n;
  sort_pairs();
  count_pairs();
}

void FractureSolver::count_pairs() {
  // Collective. Each element's listed pairs, from its owner (which lists all of them).
  listed_pairs_.assign(block_.size(), 0);
  const int rank = decomp_.rank();
  for (const auto& [a, b] : pairs_)
    for (const int s : {a, b}) {
      const std::size_t e = static_cast<std::size_t>(spheres_[static_cast<std::size_t>(s)].element);
      if (owner_[e] == rank) ++listed_pairs_[e];
    }
  if (decomp_.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, listed_pairs_.data(), static_cast<int>(listed_pairs_.size()), MPI_INT, MPI_MAX,
                  decomp_.comm());
}

void FractureSolver::update_list(double ahead) {
  if (list_stale(ahead)) {
    build_list();
  } else if (listed_spheres_ < spheres_.size()) {
    extend_list();
  }
}

PairForce FractureSolver::contact_force(std::size_t pair, const Pose& pa, const Pose& pb, double h) {
  const auto [a, b] = pairs_[pair];
  const Sphere &sa = spheres_[static_cast<std::size_t>(a)], &sb = spheres_[static_cast<std::size_t>(b)];
  const std::size_t ea = static_cast<std::size_t>(sa.element), eb = static_cast<std::size_t>(sb.element);
  PairForce out;
  const Vec3 ca = pa.x + pa.rot(sa.centre), cb = pb.x + pb.rot(sb.centre);
  const Vec3 d = ca - cb;
  const double dist = norm(d), overlap = sa.radius + sb.radius - dist;
  if (overlap <= 0 || dist == 0) return out;
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
  const double fn = std::max(0.0, k * overlap - c_eff * vn);
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
  update_list(0);
  const int rank = decomp_.rank();
  for (std::size_t p = 0; p < pairs_.size(); ++p) {
    const std::size_t ea = static_cast<std::size_t>(spheres_[static_cast<std::size_t>(pairs_[p].first)].element);
    const std::size_t eb = static_cast<std::size_t>(spheres_[static_cast<std::size_t>(pairs_[p].second)].element);
    ++contact_evaluations_;
    const PairForce f = contact_force(p, pose(ea), pose(eb), dt_);
    if (owner_[ea] == rank) F_[ea] += f.force, T_[ea] += f.torque_j;
    if (owner_[eb] == rank) F_[eb] -= f.force, T_[eb] += f.torque_i;
  }
}

}  // namespace tessera
