// SPDX-License-Identifier: MIT
#include "fracture/fracture_solver.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>

#include "core/all_gather.hpp"
#include "core/errors.hpp"
#include "core/exact_sum.hpp"

namespace tessera {

namespace {

constexpr int kSyncWidth = 22;      // x, q, v, w, L, F, T
constexpr int kBondWidth = 10;      // 3 x (slip xi, slip eta, u_max), broken

}  // namespace

double Borehole::pressure(double t) const {
  constexpr double pi = std::numbers::pi;
  if (t < 0) return 0;
  if (t <= rise) {
    const double c = std::cos(0.5 * pi * (t / rise - 1));
    return p0 * c * c;
  }
  if (t <= (fall + 1) * rise) return p0 * std::cos(0.5 * pi / fall * (t / rise - 1));
  return 0;
}

FractureSolver::FractureSolver(const Decomposition& decomp, BondedBlock block, FractureSettings settings,
                               std::optional<Borehole> hole)
    : decomp_(decomp), block_(std::move(block)), settings_(settings), hole_(hole) {
  if (!settings_.bond.valid())
    throw InputError("blast.bond.tensile_strength", std::to_string(settings_.bond.tensile_strength),
                     "positive and below sqrt(2 G_f k_n) = " +
                         std::to_string(std::sqrt(2 * settings_.bond.fracture_energy * settings_.bond.kn) / 1e6) +
                         " MPa, so that the softening branch exists (docs/theory.md B4)");
  const std::size_t n = block_.size();
  // Each face's levers about the principal axes (the largest |e_a x r|^2 of its vertices) and its area.
  face_k_.resize(n);
  for (std::size_t e = 0; e < n; ++e)
    for (int f = 0; f < 4; ++f) {
      Vec3 nf, c;
      double a;
      face_frame(block_, static_cast<int>(e), f, nf, c, a);
      auto& fk = face_k_[e][static_cast<std::size_t>(f)];
      for (int ax = 0; ax < 3; ++ax) {
        double arm2 = 0;
        for (int j = 0; j < 3; ++j) {
          const Vec3& r = block_.vertices[e][kFaceVertices[f][j]];
          arm2 = std::max(arm2, norm2(r) - r[ax] * r[ax]);
        }
        fk[static_cast<std::size_t>(ax)] = arm2;
      }
      fk[3] = a;
    }
  element_bonds_.assign(n, {});
  for (std::size_t b = 0; b < block_.bonds.size(); ++b)
    for (int e : {block_.bonds[b].master, block_.bonds[b].slave})
      element_bonds_[static_cast<std::size_t>(e)].push_back(static_cast<int>(b));
  reach_.assign(n, 0.0);
  for (std::size_t e = 0; e < n; ++e)
    for (const Vec3& p : block_.vertices[e]) reach_[e] = std::max(reach_[e], norm(p));
  choose_steps();
  // Owners (element_partition.hpp), from the work of the levels just chosen.
  work_ = element_work(block_, settings_.stepping == Stepping::stability ? stable_level_ : std::vector<int>(n, 0));
  if (static_cast<std::size_t>(decomp_.size()) > n)  // on every rank, before rank 0 alone partitions
    throw InputError("ranks", std::to_string(decomp_.size()), "at most one rank per element (" + std::to_string(n) + ")");
  assign_owners();
  x_ = block_.x0, q_ = block_.q0;
  v_.assign(n, {}), w_.assign(n, {}), L_.assign(n, {}), F_.assign(n, {}), T_.assign(n, {});
  bond_state_.assign(block_.bonds.size(), {});
  broken_.assign(block_.bonds.size(), 0);
  pose_cache_.resize(n), pose_epoch_.assign(n, -1);
  element_spheres_.assign(n, {});
  skin_ = 0.1 * block_.min_edge;
  travel_.assign(n, 0.0);
  add_surface_spheres();
  if (hole_) {
    // Faces on the hole: every node within 0.1 % of the radius from the axis, facing the axis.
    for (std::size_t s = 0; s < block_.surface.size(); ++s) {
      const SurfaceFace& f = block_.surface[s];
      bool on = true;
      for (int k = 0; k < 3; ++k) {
        const Vec3 d = block_.nodes[static_cast<std::size_t>(f.nodes[k])] - hole_->centre;
        const double r = norm(d - hole_->axis * dot(d, hole_->axis));
        on = on && std::fabs(r - hole_->radius) <= 1e-3 * hole_->radius;
      }
      if (!on) continue;
      const std::size_t e = static_cast<std::size_t>(f.element);
      const Vec3 c = block_.x0[e] + block_.q0[e].rotate(f.centroid_body) - hole_->centre;
      const Vec3 radial = c - hole_->axis * dot(c, hole_->axis);
      if (dot(block_.q0[e].rotate(f.normal_body), radial) < 0) hole_faces_.push_back(static_cast<int>(s));
    }
    if (hole_faces_.empty()) throw InputError("blast.borehole", "", "a hole whose surface is made of mesh faces (none lies on it)");
    // B8a: the rock the hole took out, over the hole faces' extent along the axis.
    double lo = 1e300, hi = -1e300;
    for (int s : hole_faces_)
      for (int k : block_.surface[static_cast<std::size_t>(s)].nodes) {
        const double a = dot(block_.nodes[static_cast<std::size_t>(k)] - hole_->centre, hole_->axis);
        lo = std::min(lo, a), hi = std::max(hi, a);
      }
    hole_mass_ = settings_.density * std::numbers::pi * hole_->radius * hole_->radius * (hi - lo);
    double block_mass = 0;
    for (double m : block_.mass) block_mass += m;
    if (block_mass < hole_mass_)
      throw InputError("blast.borehole.radius", std::to_string(hole_->radius),
                       "a block heavier than the rock its hole took out (B8a: the gas pushes only fragments heavier "
                       "than that)");
  }
  update_fragments();
}

double FractureSolver::element_limit(std::size_t e) const {
  // B9: the stiffest an element can be held: every face bonded (k_n A) and pressed by all its
  // contact spheres (n_s k_c), for translation and, about each principal axis a (a spring at r has
  // the lever |e_a x r|^2 = |r|^2 - r_a^2), for rotation: 1 / (the largest angular frequency).
  const int d = settings_.sphere_divisions;
  const double ns = (d - 1) * (d - 2) / 2.0;
  double k = 0, k_rot[3] = {0, 0, 0};
  for (int f = 0; f < 4; ++f) {
    const double kf = settings_.bond.kn * face_k_[e][static_cast<std::size_t>(f)][3] + ns * settings_.contact_stiffness;
    k += kf;
    for (int ax = 0; ax < 3; ++ax) k_rot[ax] += kf * face_k_[e][static_cast<std::size_t>(f)][ax];
  }
  const Vec3& I = block_.inertia[e];
  return std::min({std::sqrt(block_.mass[e] / k), std::sqrt(I.x / k_rot[0]), std::sqrt(I.y / k_rot[1]),
                   std::sqrt(I.z / k_rot[2])});
}

double FractureSolver::acting_limit(std::size_t e, double pairs, const Vec3& levers) const {
  // B9a: the springs that act now. The intact bonds' k_n A on their faces: the largest of their
  // translational and per-axis rotational frequencies (B9's form). The contact pairs that may touch:
  // each a spring k_c along n at the sphere's centre r, a rank-one stiffness whose frequency squared
  // is k_c (1/m + sum_a (r x n)_a^2 / I_a) exactly; `levers` sums (r x n)_a^2 over the pairs. The
  // squares add (the largest eigenvalue of a sum is at most the sum of theirs).
  double k = 0, k_rot[3] = {0, 0, 0};
  for (int b : element_bonds_[e]) {
    if (!broken_.empty() && broken_[static_cast<std::size_t>(b)]) continue;  // (none yet at set-up)
    const BondGeometry& g = block_.bonds[static_cast<std::size_t>(b)];
    const auto& fk = face_k_[e][static_cast<std::size_t>(g.master == static_cast<int>(e) ? g.master_face : g.slave_face)];
    const double kf = settings_.bond.kn * fk[3];
    k += kf;
    for (int ax = 0; ax < 3; ++ax) k_rot[ax] += kf * fk[ax];
  }
  const Vec3& I = block_.inertia[e];
  const double m = block_.mass[e];
  const double bonds = std::max({k / m, k_rot[0] / I.x, k_rot[1] / I.y, k_rot[2] / I.z});
  const double contacts = settings_.contact_stiffness * (pairs / m + levers.x / I.x + levers.y / I.y + levers.z / I.z);
  const double omega2 = bonds + contacts;
  if (omega2 == 0) return 1e300;  // free: no spring acts on it
  return 1 / std::sqrt(omega2);
}

double FractureSolver::stable_dt() const {
  double t = 1e300;
  for (std::size_t e = 0; e < block_.size(); ++e) t = std::min(t, element_limit(e));
  return settings_.stability_factor * t;
}

void FractureSolver::choose_steps() {
  const std::size_t n = block_.size();
  dt_ = settings_.time_step ? *settings_.time_step : stable_dt();
  if (settings_.stepping == Stepping::stability) {
    // The macro step: the largest element's stable step (unless set); each element's level from its own.
    // With the bond dashpots implicit (B9a), the limits of the springs that act: here every bond.
    const bool acting = settings_.implicit_damping && settings_.damping;
    std::vector<double> limit(n);
    b9_limit_.assign(acting ? n : 0, 0.0);
    double largest = 0;
    for (std::size_t e = 0; e < n; ++e) {
      limit[e] = settings_.stability_factor * (acting ? acting_limit(e, 0, {}) : element_limit(e));
      if (acting) b9_limit_[e] = element_limit(e);
      if (limit[e] < 1e299) largest = std::max(largest, limit[e]);
    }
    if (!settings_.time_step) dt_ = largest;
    stable_level_.assign(n, 0);
    for (std::size_t e = 0; e < n; ++e) stable_level_[e] = level_for(limit[e]);
  }
  // B9b: each element's freezing angle, at most a tenth of the theta method's margin for its
  // stiffest dashpot mode. With every bond intact, x = h c / m <= h (max(c_n, c_s) / k_n) omega^2,
  // omega the element's bonds' highest frequency (1 / acting_limit); the trapezoidal rule reverses
  // such a mode with |r| ~ 1 - 4 / x, and a matrix off by a fraction d moves r by about 2 d: d = 2
  // angle stays a tenth of 2 / x for angle <= 0.1 / x, i.e. 0.1 limit^2 / (h ratio).
  // Kept as cos(angle / 2), the test's form.
  frozen_cos_.assign(settings_.implicit_damping && settings_.damping ? n : 0, 1.0);
  const double ratio = std::max(settings_.bond.cn, settings_.bond.cs) / settings_.bond.kn;
  for (std::size_t e = 0; e < frozen_cos_.size(); ++e) {
    const double limit = acting_limit(e, 0, {});
    double angle = settings_.damping_frozen_angle;
    if (limit < 1e299) angle = std::min(angle, 0.1 * limit * limit / (settings_.damping_interval * dt_ * ratio));
    frozen_cos_[e] = std::cos(0.5 * angle);
  }
}

int FractureSolver::level_for(double limit) const {
  int k = 0;
  while (k < settings_.max_level && std::ldexp(dt_, -k) > limit) ++k;
  return k;
}

void FractureSolver::setup(bool fresh) {
  const std::size_t n = block_.size();
  level_.assign(n, 0);
  t_el_.assign(n, time_);
  S_.assign(n, {}), A_.assign(n, {});
  for (std::size_t e = 0; e < block_.size(); ++e) {
    w_[e] = spin(e, q_[e].unrotate(L_[e]));
  }
  exchange();
  if (!fresh) return;  // a restart keeps the forces of the checkpoint (restore)
  compute_forces(time_);
  share_broken();
}

void FractureSolver::set_velocity(std::size_t e, const Vec3& v, const Vec3& w) {
  v_[e] = v;
  const Vec3 wb = q_[e].unrotate(w);
  const Vec3& I = block_.inertia[e];
  L_[e] = q_[e].rotate({I.x * wb.x, I.y * wb.y, I.z * wb.z});
  w_[e] = w;
}


void FractureSolver::step() {
  if (settings_.stepping != Stepping::uniform) return multirate_step();
  {
    auto t = timers_.scope("kick_drift");
    kick(0.5 * dt_);
    drift();
  }
  {
    auto t = timers_.scope("exchange");
    exchange();
  }
  compute_forces(time_ + dt_);
  {
    auto t = timers_.scope("kick");
    kick(0.5 * dt_);
  }
  {
    auto t = timers_.scope("damping");
    if ((steps_ + 1) % settings_.damping_interval == 0) damp_bonds(settings_.damping_interval * dt_);  // B9c
  }
  {
    auto t = timers_.scope("broken");
    share_broken();
  }
  time_ += dt_;
  ++steps_;
  element_steps_ += static_cast<long>(owned_by_rank_[static_cast<std::size_t>(decomp_.rank())].size());
}

void FractureSolver::kick(double h) {
  for (int e : owned_by_rank_[static_cast<std::size_t>(decomp_.rank())]) {
    const std::size_t i = static_cast<std::size_t>(e);
    v_[i] += F_[i] * (h / block_.mass[i]);
    L_[i] += T_[i] * h;
    w_[i] = spin(i, q_[i].unrotate(L_[i]));
  }
}

void FractureSolver::drift() {
  for (int e : owned_by_rank_[static_cast<std::size_t>(decomp_.rank())]) {
    const std::size_t i = static_cast<std::size_t>(e);
    const Vec3 x_old = x_[i];
    const Quaternion q_old = q_[i];
    x_[i] += v_[i] * dt_;
    Vec3 Lb = q_[i].unrotate(L_[i]);
    free_rotation_step(q_[i], Lb, block_.inertia[i], dt_);
    L_[i] = q_[i].rotate(Lb);
    w_[i] = spin(i, Lb);
    add_travel(i, x_old, q_old);
  }
}

// Every rank's owned states to every rank (Allgatherv of `width` values per element).
namespace {
template <class Pack, class Unpack>
void all_gather_elements(MPI_Comm comm, int rank, const std::vector<std::vector<int>>& owned, int width, Pack pack,
                         Unpack unpack, GatherBuffers& buf) {
  const int P = static_cast<int>(owned.size());
  std::vector<int>& counts = buf.counts;
  std::vector<int>& displs = buf.displs;
  counts.resize(static_cast<std::size_t>(P)), displs.resize(static_cast<std::size_t>(P));
  int total = 0;
  for (int r = 0; r < P; ++r) {
    counts[static_cast<std::size_t>(r)] = width * static_cast<int>(owned[static_cast<std::size_t>(r)].size());
    displs[static_cast<std::size_t>(r)] = total;
    total += counts[static_cast<std::size_t>(r)];
  }
  std::vector<double>& mine = buf.mine;
  mine.resize(static_cast<std::size_t>(counts[static_cast<std::size_t>(rank)]));
  std::size_t k = 0;
  for (int e : owned[static_cast<std::size_t>(rank)]) pack(e, &mine[k]), k += static_cast<std::size_t>(width);
  std::vector<double>& all = buf.all;
  all.resize(static_cast<std::size_t>(total));
  MPI_Allgatherv(mine.data(), counts[static_cast<std::size_t>(rank)], MPI_DOUBLE, all.data(), counts.data(),
                 displs.data(), MPI_DOUBLE, comm);
  for (int r = 0; r < P; ++r) {
    if (r == rank) continue;
    std::size_t at = static_cast<std::size_t>(displs[static_cast<std::size_t>(r)]);
    for (int e : owned[static_cast<std::size_t>(r)]) unpack(e, &all[at]), at += static_cast<std::size_t>(width);
  }
}
}  // namespace

void FractureSolver::exchange() {
  if (decomp_.size() > 1) exchange_elements(owned_by_rank_);
}

void FractureSolver::pack_state(std::size_t i, bool momentum, double* o) const {
  const Quaternion& q = q_[i];
  const Vec3& r = momentum ? L_[i] : w_[i];
  const double s[kStateWidth] = {x_[i].x, x_[i].y, x_[i].z, q.w, q.x, q.y, q.z,
                                 v_[i].x, v_[i].y, v_[i].z, r.x, r.y, r.z, t_el_[i]};
  std::copy(s, s + kStateWidth, o);
}

void FractureSolver::unpack_state(std::size_t i, bool momentum, const double* s) {
  const Vec3 x_old = x_[i];
  const Quaternion q_old = q_[i];
  x_[i] = {s[0], s[1], s[2]}, q_[i] = {s[3], s[4], s[5], s[6]};
  add_travel(i, x_old, q_old);
  v_[i] = {s[7], s[8], s[9]}, t_el_[i] = s[13];
  if (momentum) {
    L_[i] = {s[10], s[11], s[12]};
    w_[i] = spin(i, q_[i].unrotate(L_[i]));
  } else {
    w_[i] = {s[10], s[11], s[12]};
  }
}

void FractureSolver::exchange_elements(const std::vector<std::vector<int>>& lists) {
  // Uniform steps send the spin w as the owner computed it. Per-element levels send the angular
  // momentum L instead: a rank drifts the other ranks' elements its pairs read (multirate_step), which
  // needs L, and w = spin(L) is then formed as on the owner (the same bits).
  const bool momentum = settings_.stepping != Stepping::uniform;
  all_gather_elements(
      decomp_.comm(), decomp_.rank(), lists, kStateWidth,
      [&](int e, double* o) { pack_state(static_cast<std::size_t>(e), momentum, o); },
      [&](int e, const double* s) { unpack_state(static_cast<std::size_t>(e), momentum, s); }, gather_);
}

void FractureSolver::sync_state() {
  if (decomp_.size() == 1) return;
  all_gather_elements(
      decomp_.comm(), decomp_.rank(), owned_by_rank_, kSyncWidth,
      [&](int e, double* o) {
        const std::size_t i = static_cast<std::size_t>(e);
        const Quaternion& q = q_[i];
        const double s[kSyncWidth] = {x_[i].x, x_[i].y, x_[i].z, q.w,     q.x,     q.y,     q.z,     v_[i].x,
                                      v_[i].y, v_[i].z, w_[i].x, w_[i].y, w_[i].z, L_[i].x, L_[i].y, L_[i].z,
                                      F_[i].x, F_[i].y, F_[i].z, T_[i].x, T_[i].y, T_[i].z};
        std::copy(s, s + kSyncWidth, o);
      },
      [&](int e, const double* s) {
        const std::size_t i = static_cast<std::size_t>(e);
        x_[i] = {s[0], s[1], s[2]}, q_[i] = {s[3], s[4], s[5], s[6]};
        v_[i] = {s[7], s[8], s[9]}, w_[i] = {s[10], s[11], s[12]}, L_[i] = {s[13], s[14], s[15]};
        F_[i] = {s[16], s[17], s[18]}, T_[i] = {s[19], s[20], s[21]};
      },
      gather_);
  // Bonds: the master's owner holds the current state.
  std::vector<std::vector<int>> bonds_by_rank(static_cast<std::size_t>(decomp_.size()));
  for (std::size_t b = 0; b < block_.bonds.size(); ++b)
    bonds_by_rank[static_cast<std::size_t>(owner_[static_cast<std::size_t>(block_.bonds[b].master)])].push_back(
        static_cast<int>(b));
  all_gather_elements(
      decomp_.comm(), decomp_.rank(), bonds_by_rank, kBondWidth,
      [&](int b, double* o) {
        const auto& s = bond_state_[static_cast<std::size_t>(b)];
        for (int k = 0; k < 3; ++k) o[3 * k] = s[k].slip[0], o[3 * k + 1] = s[k].slip[1], o[3 * k + 2] = s[k].u_max;
        o[9] = broken_[static_cast<std::size_t>(b)];
      },
      [&](int b, const double* o) {
        auto& s = bond_state_[static_cast<std::size_t>(b)];
        for (int k = 0; k < 3; ++k) s[k].slip[0] = o[3 * k], s[k].slip[1] = o[3 * k + 1], s[k].u_max = o[3 * k + 2];
      },
      gather_);
}

void FractureSolver::restore(const std::vector<Vec3>& x, const std::vector<Quaternion>& q, const std::vector<Vec3>& v,
                             const std::vector<Vec3>& L, const std::vector<std::array<BondVertex, 3>>& bonds,
                             const std::vector<char>& broken, const ContactListState& list,
                             const std::vector<Vec3>& F, const std::vector<Vec3>& T) {
  bond_state_ = bonds;
  F_ = F, T_ = T;
  spheres_.clear(), pairs_.clear(), unlisted_bonds_.clear();
  sunk_.clear(), opened_.clear();
  born_overlaps_ = decomp_.rank() == 0 ? list.born_overlaps : 0;  // the sum over the ranks
  deepest_born_ = list.deepest_born_overlap;
  element_spheres_.assign(block_.size(), {});
  max_radius_ = 0;
  add_surface_spheres();
  broken_.assign(block_.bonds.size(), 0);
  // The spheres of faces the list already held, then those of faces released after it was last
  // made, in the order they broke (they join the list at the next step, as they would have).
  std::vector<char> unlisted(block_.bonds.size(), 0);
  for (int b : list.unlisted) unlisted[static_cast<std::size_t>(b)] = 1;
  for (std::size_t b = 0; b < broken.size(); ++b)
    if (broken[b] && !unlisted[b]) broken_[b] = 1, add_spheres(static_cast<int>(b));
  unlisted_bonds_.clear();
  listed_spheres_ = spheres_.size();
  for (int b : list.unlisted) broken_[static_cast<std::size_t>(b)] = 1, add_spheres(b);
  update_fragments();
  // The checkpoint names spheres by key; a pair is this rank's if one of its elements is.
  std::unordered_map<long, int> by_key;
  for (std::size_t k = 0; k < spheres_.size(); ++k) by_key[spheres_[k].key] = static_cast<int>(k);
  const int rank = decomp_.rank();
  const auto mine = [&](long ka, long kb) {
    return owner_[static_cast<std::size_t>(spheres_[static_cast<std::size_t>(by_key.at(ka))].element)] == rank ||
           owner_[static_cast<std::size_t>(spheres_[static_cast<std::size_t>(by_key.at(kb))].element)] == rank;
  };
  // B7b: the depths of the pairs this rank lists, so that every rank holding a pair holds it.
  for (const auto& [keys, depth] : list.sunk)
    if (mine(keys.first, keys.second)) sunk_[keys] = depth;
  build_x_.clear(), build_q_.clear();
  if (!list.stale && list.x.size() == block_.size()) {
    // The list as the interrupted run had it (the per-element levels depend on which pairs are
    // listed, not only on which touch): its pairs by sphere key, the cells and the poses of its
    // last build.
    build_x_ = list.x, build_q_ = list.q;
    x_ = list.x, q_ = list.q;
    cell_radius_ = list.cell_radius;
    reset_grid();
    for (std::size_t k = 0; k < listed_spheres_; ++k) insert_sphere(k, sphere_position(k));
    for (const auto& [ka, kb] : list.pairs) {
      if (!mine(ka, kb)) continue;
      const auto it = sunk_.find({ka, kb});
      ListedPair lp = listed_pair(by_key.at(ka), by_key.at(kb));
      lp.sunk = it == sunk_.end() ? 0.0 : it->second;
      pairs_.push_back(lp);
    }
    sort_pairs();
  }
  count_pairs();
  x_ = x, q_ = q, v_ = v, L_ = L;
}

ContactListState FractureSolver::contact_list_state() const {
  ContactListState s{build_x_, build_q_, build_x_.empty(), {}, unlisted_bonds_, cell_radius_, {}, born_overlaps(),
                     deepest_born_overlap()};
  // Every rank's pairs, each once (a pair across ranks is on both), by key.
  std::vector<long> mine;
  for (const ListedPair& lp : pairs_)
    mine.insert(mine.end(), {spheres_[static_cast<std::size_t>(lp.first)].key, spheres_[static_cast<std::size_t>(lp.second)].key});
  const std::vector<long> all = all_gather_concat(decomp_.comm(), mine);
  for (std::size_t k = 0; k + 1 < all.size(); k += 2) s.pairs.push_back({all[k], all[k + 1]});
  std::sort(s.pairs.begin(), s.pairs.end());
  s.pairs.erase(std::unique(s.pairs.begin(), s.pairs.end()), s.pairs.end());
  s.sunk = all_sunk();
  return s;
}

std::vector<Quaternion> FractureSolver::damping_frozen() const {
  std::vector<Quaternion> q = frozen_q_.size() == block_.size() ? frozen_q_ : q_;
  if (decomp_.size() == 1) return q;
  GatherBuffers buf;
  all_gather_elements(
      decomp_.comm(), decomp_.rank(), owned_by_rank_, 4,
      [&](int e, double* o) {
        const Quaternion& a = q[static_cast<std::size_t>(e)];
        o[0] = a.w, o[1] = a.x, o[2] = a.y, o[3] = a.z;
      },
      [&](int e, const double* s) { q[static_cast<std::size_t>(e)] = {s[0], s[1], s[2], s[3]}; }, buf);
  return q;
}

std::vector<std::pair<std::pair<long, long>, double>> FractureSolver::all_sunk() const {
  // B7b: every rank's sunk pairs, each once (the ranks that hold a pair hold the same depth).
  std::vector<long> keys;
  std::vector<double> depths;
  for (const auto& [k, d] : current_sunk()) keys.insert(keys.end(), {k.first, k.second}), depths.push_back(d);
  const std::vector<long> all_keys = all_gather_concat(decomp_.comm(), keys);
  const std::vector<double> all_depths = all_gather_concat(decomp_.comm(), depths);
  std::map<std::pair<long, long>, double> merged;
  for (std::size_t k = 0; k < all_depths.size(); ++k) merged[{all_keys[2 * k], all_keys[2 * k + 1]}] = all_depths[k];
  return {merged.begin(), merged.end()};
}

long FractureSolver::born_overlaps() const {
  long n = born_overlaps_;
  MPI_Allreduce(MPI_IN_PLACE, &n, 1, MPI_LONG, MPI_SUM, decomp_.comm());
  return n;
}

double FractureSolver::deepest_born_overlap() const {
  double d = deepest_born_;
  MPI_Allreduce(MPI_IN_PLACE, &d, 1, MPI_DOUBLE, MPI_MAX, decomp_.comm());
  return d;
}

std::size_t FractureSolver::sunk_pairs() const { return all_sunk().size(); }

const FractureSolver::Pose& FractureSolver::pose(std::size_t e) {
  if (pose_epoch_[e] != epoch_) {
    pose_cache_[e] = make_pose(x_[e], v_[e], w_[e], q_[e]);
    pose_epoch_[e] = epoch_;
  }
  return pose_cache_[e];
}

void FractureSolver::compute_forces(double time) {
  new_epoch();
  for (int e : owned_by_rank_[static_cast<std::size_t>(decomp_.rank())])
    F_[static_cast<std::size_t>(e)] = {}, T_[static_cast<std::size_t>(e)] = {};
  {
    auto t = timers_.scope("bond_forces");
    bond_forces();
  }
  if (!spheres_.empty()) {
    auto t = timers_.scope("contact_list");
    update_list(0);  // the uniform step checks the list every step
  }
  {
    auto t = timers_.scope("contact_forces");
    contact_forces();
  }
  {
    auto t = timers_.scope("borehole");
    borehole_forces(time);
  }
}

PairForce FractureSolver::bond_force(std::size_t b, const Pose& pi, const Pose& pj) {
  const BondLaw& law = settings_.bond;
  const bool explicit_dashpots = settings_.damping && !settings_.implicit_damping;
  const double cn = explicit_dashpots ? law.cn : 0, cs = explicit_dashpots ? law.cs : 0;
  const BondGeometry& g = block_.bonds[b];
  const Vec3 n = pi.rot(g.normal), xi = pi.rot(g.xi), eta = pi.rot(g.eta);
  const double share = g.area / 3, u_failure = law.u_failure();
  PairForce out;
  for (int k = 0; k < 3; ++k) {
    const Vec3 ri = pi.rot(g.at_master[k]), rj = pj.rot(g.at_slave[k]);
    const Vec3 u = (pj.x + rj) - (pi.x + ri);
    const Vec3 du = (pj.v + cross(pj.w, rj)) - (pi.v + cross(pi.w, ri));
    const double un = dot(u, n);
    const double ut[2] = {dot(u, xi), dot(u, eta)};
    BondVertex& s = bond_state_[b][static_cast<std::size_t>(k)];
    const double sigma = bond_normal_stress(law, s, un);
    double tau[2];
    bond_shear_stress(law, s, ut, sigma, tau);
    const double dun = dot(du, n);
    const Vec3 dut = du - n * dun;
    const Vec3 F = (n * (sigma + cn * dun) + xi * tau[0] + eta * tau[1] + dut * cs) * (-share);
    out.force += F;
    out.torque_j += cross(rj, F);
    out.torque_i -= cross(ri, F);
    out.failed = out.failed || un >= u_failure;
  }
  return out;
}

void FractureSolver::bond_forces() {
  const int rank = decomp_.rank();
  newly_broken_.clear();
  for (std::size_t b = 0; b < block_.bonds.size(); ++b) {
    if (broken_[b]) continue;
    const BondGeometry& g = block_.bonds[b];
    const std::size_t i = static_cast<std::size_t>(g.master), j = static_cast<std::size_t>(g.slave);
    const bool own_i = owner_[i] == rank, own_j = owner_[j] == rank;
    if (!own_i && !own_j) continue;
    ++bond_evaluations_;
    const PairForce f = bond_force(b, pose(i), pose(j));
    if (own_j) F_[j] += f.force, T_[j] += f.torque_j;
    if (own_i) F_[i] -= f.force, T_[i] += f.torque_i;
    if (f.failed && own_i) newly_broken_.push_back(static_cast<int>(b));
  }
}

void FractureSolver::share_broken() {
  std::vector<int> all = all_gather_concat(decomp_.comm(), newly_broken_);
  std::sort(all.begin(), all.end());
  for (int b : all) {
    broken_[static_cast<std::size_t>(b)] = 1;
    add_spheres(b);
  }
  newly_broken_.clear();
  if (!all.empty()) update_fragments();
}

void FractureSolver::update_fragments() {
  // B8a: every rank holds every bond's state, so every rank finds the same fragments.
  find_fragments(block_, broken_, fragments_);
  hole_loaded_.assign(block_.size(), 0);
  for (std::size_t e = 0; e < block_.size(); ++e)
    hole_loaded_[e] = fragments_.mass[static_cast<std::size_t>(fragments_.label[e])] >= hole_mass_;
}

long FractureSolver::unloaded_hole_faces() const {
  long n = 0;
  for (int s : hole_faces_) n += !hole_loaded_[static_cast<std::size_t>(block_.surface[static_cast<std::size_t>(s)].element)];
  return n;
}

long FractureSolver::broken_count() const {
  long n = 0;
  for (char c : broken_) n += c;
  return n;
}

void FractureSolver::borehole_forces(double t) {
  if (!hole_) return;
  const double p = hole_->pressure(t);
  if (p == 0) return;
  const int rank = decomp_.rank();
  for (int s : hole_faces_) {
    const std::size_t e = static_cast<std::size_t>(block_.surface[static_cast<std::size_t>(s)].element);
    Vec3 F, T;
    if (owner_[e] == rank && hole_load(s, p, F, T)) F_[e] += F, T_[e] += T;
  }
}

bool FractureSolver::hole_load(int s, double p, Vec3& F, Vec3& T) const {
  const SurfaceFace& f = block_.surface[static_cast<std::size_t>(s)];
  const std::size_t e = static_cast<std::size_t>(f.element);
  if (!hole_loaded_[e]) return false;
  F = q_[e].rotate(f.normal_body) * (-p * f.area);
  T = cross(q_[e].rotate(f.centroid_body), F);
  return true;
}

FractureEnergies FractureSolver::energies() const {
  const int rank = decomp_.rank();
  ExactSum kin, bond, contact;
  for (int e : owned_by_rank_[static_cast<std::size_t>(rank)]) {
    const std::size_t i = static_cast<std::size_t>(e);
    kin += 0.5 * block_.mass[i] * norm2(v_[i]) + 0.5 * dot(L_[i], w_[i]);
  }
  const BondLaw& law = settings_.bond;
  for (std::size_t b = 0; b < block_.bonds.size(); ++b) {
    const BondGeometry& g = block_.bonds[b];
    const std::size_t i = static_cast<std::size_t>(g.master), j = static_cast<std::size_t>(g.slave);
    if (broken_[b] || owner_[i] != rank) continue;
    const Vec3 n = q_[i].rotate(g.normal), xi = q_[i].rotate(g.xi), eta = q_[i].rotate(g.eta);
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = (x_[j] + q_[j].rotate(g.at_slave[k])) - (x_[i] + q_[i].rotate(g.at_master[k]));
      const BondVertex& s = bond_state_[b][static_cast<std::size_t>(k)];
      const double un = dot(u, n), d0 = dot(u, xi) - s.slip[0], d1 = dot(u, eta) - s.slip[1];
      bond += g.area / 3 * 0.5 * (law.kn * un * un + law.ks * (d0 * d0 + d1 * d1));
    }
  }
  for (const ListedPair& lp : pairs_) {
    const Sphere &sa = spheres_[static_cast<std::size_t>(lp.first)], &sb = spheres_[static_cast<std::size_t>(lp.second)];
    const std::size_t ea = static_cast<std::size_t>(sa.element), eb = static_cast<std::size_t>(sb.element);
    if (owner_[ea] != rank) continue;  // each pair once: by the owner of its first sphere's element
    const double overlap =
        sa.radius + sb.radius - norm(x_[ea] + q_[ea].rotate(sa.centre) - x_[eb] - q_[eb].rotate(sb.centre)) - lp.sunk;
    if (overlap > 0) contact += 0.5 * settings_.contact_stiffness * overlap * overlap;  // beyond the sunk depth (B7b)
  }
  std::array<ExactSum, 3> sums{kin, bond, contact};
  ExactSum::all_reduce(sums, decomp_.comm());
  return {sums[0].value(), sums[1].value(), sums[2].value()};
}

}  // namespace tessera
