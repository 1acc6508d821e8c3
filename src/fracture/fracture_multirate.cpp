// SPDX-License-Identifier: MIT
// Per-element time steps with shared impulses (the seed's section 3.1, eq. 3; docs/theory.md B10).
//
// A macro step dt0 is cut into 2^K sub-steps of dt0 / 2^K. Element e has a level k_e and a step
// h_e = dt0 / 2^k_e: it is due at the sub-steps that are multiples of h_e. Its trajectory is
// piecewise linear: x(t) = x_e + v_e (t - t_e) between its updates (t_e its last one), turning at
// w_e. A pair (bond or contact) is evaluated whenever its finer element is due (level max(k_i, k_j),
// step h_p = min(h_i, h_j)), at both elements' positions at that time, and its impulse F h_p is
// added to both elements' sums S (equal and opposite: momentum is conserved to round-off). A due
// element then takes its sum, v <- v + S / m (eq. 3; L <- L + the angular impulse), and drifts over
// h_e (T9 for the rotation). With a single level this is the symplectic Euler (leapfrog) step.
//
// Two ways to apply the impulses:
//   travel     (the seed, scheme b) a due element takes the sum of the impulses of its last step;
//   stability  (scheme c) an element takes each impulse when it is made (the asynchronous
//              variational integrator of Lew, Marsden, Ortiz & West 2003: momentum-conserving and
//              symplectic), so a coarse element bonded to a fine one follows it without lag. A
//              sub-step drifts its due elements to t (T9 for the rotation), evaluates the due pairs
//              at those states, then kicks them: pairs read the states the elements have, with no
//              extrapolation. Travel levels evaluate pairs on the piecewise-linear paths above.
// Levels are chosen at each macro step, when every element is due:
//   travel     the seed's rule: the smallest k with |v_e| dt0 / 2^k <= l (l = blast.travel_limit)
//   stability  each element's own stable step (B9: its faces' springs and its mass and inertia)
//              times blast.stability_factor, rounded down to dt0 / 2^k
// Faces that fail are released at once on the ranks that evaluate them and made known to all at
// the end of the macro step (their contact spheres join then). Every rank knows every element's
// level, so the states of the due elements travel in one all-gather per sub-step without counts.
#include <algorithm>
#include <bit>
#include <cmath>

#include "fracture/fracture_solver.hpp"

namespace tessera {

namespace {
constexpr std::size_t kPrefetchAhead = 8;
}  // namespace

FractureSolver::Pose FractureSolver::pose_ahead(std::size_t e, double t) const {
  // Built for each pair: with a few pairs per element and sub-step a cache costs more memory
  // traffic than it saves (measured on 100,000 elements).
  const double h = t - t_el_[e];
  Quaternion q = q_[e];
  const double wn = norm(w_[e]);
  if (wn > 0) {
    double s, c;
    small_angle_sincos(0.5 * wn * h, s, c);
    const Vec3 a = w_[e] * (s / wn);
    q = Quaternion{c, a.x, a.y, a.z} * q_[e];
  }
  return make_pose(x_[e] + v_[e] * h, v_[e], w_[e], q);
}

void FractureSolver::prefetch_bond(std::size_t b) const {
  const char* g = reinterpret_cast<const char*>(&block_.bonds[b]);
  for (std::size_t line = 0; line < sizeof(BondGeometry); line += 64) __builtin_prefetch(g + line);
  const char* st = reinterpret_cast<const char*>(&bond_state_[b]);
  __builtin_prefetch(st), __builtin_prefetch(st + sizeof(bond_state_[b]) - 1);
}

void FractureSolver::prefetch_pair(std::size_t p) const {
  const ListedPair& lp = pairs_[p];
  __builtin_prefetch(&spheres_[static_cast<std::size_t>(lp.first)]);
  __builtin_prefetch(&spheres_[static_cast<std::size_t>(lp.second)]);
}

template <int W>
void FractureSolver::drift(const int* e, double t) {
  // x += v h; the free rotation over h (T9); the travel (B7a); the clock; the spin at the new pose.
  // W elements at once (free_rotation_steps: each one's operations as alone, the same bits).
  Quaternion q[W];
  Vec3 Lb[W], I[W], x_old[W];
  double h[W];
  for (int b = 0; b < W; ++b) {
    const std::size_t i = static_cast<std::size_t>(e[b]);
    h[b] = t - t_el_[i];
    x_old[b] = x_[i];
    x_[i] += v_[i] * h[b];
    q[b] = q_[i];
    Lb[b] = q_[i].unrotate(L_[i]);
    I[b] = block_.inertia[i];
  }
  free_rotation_steps<W>(q, Lb, I, h);
  for (int b = 0; b < W; ++b) {
    const std::size_t i = static_cast<std::size_t>(e[b]);
    const Quaternion q_old = q_[i];
    q_[i] = q[b];
    L_[i] = q_[i].rotate(Lb[b]);
    add_travel(i, x_old[b], q_old);
    t_el_[i] = t;
    w_[i] = spin(i, q_[i].unrotate(L_[i]));
  }
}

void FractureSolver::advance_to(std::size_t i, double t) {
  if (t - t_el_[i] > 0) {
    const int e = static_cast<int>(i);
    return drift<1>(&e, t);
  }
  t_el_[i] = t;
  w_[i] = spin(i, q_[i].unrotate(L_[i]));
}

void FractureSolver::advance_all(const std::vector<int>& elements, double t) {
  // advance_to on each; those that move kBatch at a time.
  int at[kBatch];
  int n = 0;
  for (int e : elements) {
    if (t - t_el_[static_cast<std::size_t>(e)] > 0) {
      at[n++] = e;
      if (n == kBatch) drift<kBatch>(at, t), n = 0;
    } else {
      advance_to(static_cast<std::size_t>(e), t);
    }
  }
  for (int b = 0; b < n; ++b) drift<1>(&at[b], t);
}

void FractureSolver::kick_impulse(std::size_t i) {
  // Nothing arrived (an element drawn to a finer level by pairs that are apart): v, L and the spin
  // its drift made stay as they are (adding zeros would leave their bits).
  const Vec3 &S = S_[i], &A = A_[i];
  if (S.x == 0 && S.y == 0 && S.z == 0 && A.x == 0 && A.y == 0 && A.z == 0) return;
  v_[i] += S_[i] / block_.mass[i];
  L_[i] += A_[i];
  S_[i] = {}, A_[i] = {};
  w_[i] = spin(i, q_[i].unrotate(L_[i]));
}

void FractureSolver::assign_levels() {
  const std::size_t n = block_.size();
  level_.assign(n, 0);
  if (settings_.stepping == Stepping::stability && settings_.implicit_damping && settings_.damping) {
    // B9a: each element's level from the springs that act on it this macro step, the intact bonds
    // and the listed pairs. A pair is listed on its elements' owners, so the owner counts all of an
    // element's pairs; the largest level over the ranks is the owner's.
    std::vector<double>& pairs = scratch_pairs_;
    pairs.assign(n, 0.0);
    // A listed pair counts when it may touch within the macro step: its spheres' gap now within
    // twice what its two elements can travel in dt0 at their speeds now (centroid and farthest
    // vertex's turn). From the state alone, so that a restart takes the same levels.
    std::vector<double>& speed = scratch_speed_;
    speed.resize(n);
    for (std::size_t e = 0; e < n; ++e) speed[e] = norm(v_[e]) + norm(w_[e]) * reach_[e];
    std::vector<Vec3>& levers = scratch_levers_;
    levers.assign(n, Vec3{});
    const int rank = decomp_.rank();
    for (const ListedPair& lp : pairs_) {
      const std::size_t a = static_cast<std::size_t>(lp.ea), b = static_cast<std::size_t>(lp.eb);
      const Vec3 pa = sphere_position(static_cast<std::size_t>(lp.first)), pb = sphere_position(static_cast<std::size_t>(lp.second));
      const Vec3 d = pb - pa;
      const double dist = norm(d);
      const double gap = dist - spheres_[static_cast<std::size_t>(lp.first)].radius - spheres_[static_cast<std::size_t>(lp.second)].radius;
      if (gap > 2 * dt_ * (speed[a] + speed[b])) continue;
      pairs[a] += 1, pairs[b] += 1;
      // Each side's lever (r x n) in its body frame, squared per principal axis; coincident
      // centres (no direction): the farthest vertex's reach about every axis, a bound. Only the
      // owned sides' (a pair across a cut is listed on both owners; the level is the owner's).
      for (const auto& [e, p] : {std::pair{a, pa}, std::pair{b, pb}}) {
        if (owner_[e] != rank) continue;
        if (dist == 0) {
          const double r2 = reach_[e] * reach_[e];
          levers[e] += Vec3{r2, r2, r2};
          continue;
        }
        const Vec3 t = q_[e].unrotate(cross(p - x_[e], d / dist));
        levers[e] += Vec3{t.x * t.x, t.y * t.y, t.z * t.z};
      }
    }
    // Never finer than B9's bound (every face bonded and pressed by all its spheres), which the
    // explicit scheme's levels take: a count of pairs that may touch can exceed it.
    // Each rank its own elements (the others' stay 0: the owner's level is the largest).
    for (int e : owned_by_rank_[static_cast<std::size_t>(rank)]) {
      const std::size_t i = static_cast<std::size_t>(e);
      level_[i] = level_for(settings_.stability_factor * std::max(acting_limit(i, pairs[i], levers[i]), b9_limit_[i]));
    }
    if (decomp_.size() > 1)
      MPI_Allreduce(MPI_IN_PLACE, level_.data(), static_cast<int>(n), MPI_INT, MPI_MAX, decomp_.comm());
    return;
  }
  for (std::size_t e = 0; e < n; ++e) {
    int k = 0;
    if (settings_.stepping == Stepping::travel) {
      const double speed = norm(v_[e]);
      while (k < settings_.max_level && speed * dt_ / std::ldexp(1.0, k) > settings_.travel_limit) ++k;
    } else {
      k = stable_level_[e];
    }
    level_[e] = k;
  }
}

void FractureSolver::clear_buckets(std::vector<std::vector<int>>& buckets, int count) {
  if (buckets.size() < static_cast<std::size_t>(count)) buckets.resize(static_cast<std::size_t>(count));
  for (auto& b : buckets) b.clear();
}

void FractureSolver::build_halo(int K) {
  // Every rank lists the same cross pairs (bonds and contacts between its elements and another
  // rank's), so what rank r sends me at a level is what I list as needed from r there: both sides
  // order each list by element and agree on the counts without a message.
  const int rank = decomp_.rank(), P = decomp_.size();
  HaloLists& h = halo_;
  clear_buckets(h.in, K + 1);
  h.sent.clear(), h.read.clear();
  auto cross = [&](int a, int b) {  // a's and b's owners differ; the pair is listed here: one is mine
    if (owner_[static_cast<std::size_t>(a)] != rank) std::swap(a, b);
    if (owner_[static_cast<std::size_t>(a)] != rank) return;
    const int r = owner_[static_cast<std::size_t>(b)];
    h.sent.push_back({r, a}), h.read.push_back({r, b});
  };
  for (const auto& level : bond_buckets_)
    for (int b : level) {
      const BondGeometry& g = block_.bonds[static_cast<std::size_t>(b)];
      if (owner_[static_cast<std::size_t>(g.master)] != owner_[static_cast<std::size_t>(g.slave)]) cross(g.master, g.slave);
    }
  for (const ListedPair& lp : pairs_) {
    const int a = lp.ea, b = lp.eb;
    if (owner_[static_cast<std::size_t>(a)] != owner_[static_cast<std::size_t>(b)]) cross(a, b);
  }
  for (auto* v : {&h.sent, &h.read}) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  }
  h.out.resize(static_cast<std::size_t>(P)), h.from.resize(static_cast<std::size_t>(P));
  for (int r = 0; r < P; ++r)
    clear_buckets(h.out[static_cast<std::size_t>(r)], K + 1), clear_buckets(h.from[static_cast<std::size_t>(r)], K + 1);
  // Every cross pair adds its rank to both lists: the neighbours are the ranks sent to.
  h.neighbours.clear();
  for (const auto& [r, e] : h.sent) {
    h.out[static_cast<std::size_t>(r)][static_cast<std::size_t>(kick_level_[static_cast<std::size_t>(e)])].push_back(e);
    if (h.neighbours.empty() || h.neighbours.back() != r) h.neighbours.push_back(r);
  }
  for (const auto& [r, e] : h.read) {
    const std::size_t k = static_cast<std::size_t>(kick_level_[static_cast<std::size_t>(e)]);
    h.from[static_cast<std::size_t>(r)][k].push_back(e);
    h.in[k].push_back(e);
  }
}

void FractureSolver::exchange_halo(int first, int K) {
  // After a sub-step's kicks: to each neighbour, the states of my elements due now that its pairs
  // read (pack_state with L); from it, the same of its elements.
  HaloLists& h = halo_;
  const std::size_t n = h.neighbours.size();
  h.send.resize(n), h.recv.resize(n);
  std::vector<MPI_Request>& req = h.requests;
  req.assign(2 * n, MPI_REQUEST_NULL);
  for (std::size_t m = 0; m < n; ++m) {
    const std::size_t r = static_cast<std::size_t>(h.neighbours[m]);
    std::size_t count = 0;
    for (int k = first; k <= K; ++k) count += h.from[r][static_cast<std::size_t>(k)].size();
    h.recv[m].resize(count * kStateWidth);
    if (count == 0) continue;  // it sends nothing either (the same lists): no message, no wait
    MPI_Irecv(h.recv[m].data(), static_cast<int>(h.recv[m].size()), MPI_DOUBLE, static_cast<int>(r), kHaloTag,
              decomp_.comm(), &req[m]);
  }
  for (std::size_t m = 0; m < n; ++m) {
    const std::size_t r = static_cast<std::size_t>(h.neighbours[m]);
    std::vector<double>& buf = h.send[m];
    buf.clear();
    for (int k = first; k <= K; ++k)
      for (int e : h.out[r][static_cast<std::size_t>(k)]) {
        buf.resize(buf.size() + kStateWidth);
        pack_state(static_cast<std::size_t>(e), true, buf.data() + buf.size() - kStateWidth);
      }
    if (buf.empty()) continue;
    MPI_Isend(buf.data(), static_cast<int>(buf.size()), MPI_DOUBLE, static_cast<int>(r), kHaloTag, decomp_.comm(),
              &req[n + m]);
  }
  MPI_Waitall(static_cast<int>(req.size()), req.data(), MPI_STATUSES_IGNORE);
  for (std::size_t m = 0; m < n; ++m) {
    const std::size_t r = static_cast<std::size_t>(h.neighbours[m]);
    const double* s = h.recv[m].data();
    for (int k = first; k <= K; ++k)
      for (int e : h.from[r][static_cast<std::size_t>(k)]) {
        unpack_state(static_cast<std::size_t>(e), true, s);
        s += kStateWidth;
      }
  }
}

void FractureSolver::multirate_step() {
  const int rank = decomp_.rank(), P = decomp_.size();
  // The levels from the springs that act (B9a) need the macro step's contact list first.
  const bool acting = settings_.stepping == Stepping::stability && settings_.implicit_damping && settings_.damping;
  if (!spheres_.empty() && acting) {
    auto t = timers_.scope("contact_list");
    update_list(dt_);
  }
  {
    auto t = timers_.scope("levels");
    assign_levels();
  }
  int K = 0;
  for (int k : level_) K = std::max(K, k);
  // Pairs by level (their finer element's); the list is checked with the macro step's travel ahead.
  // The buckets are members: cleared each macro step, their storage kept.
  auto& bonds = bond_buckets_;
  auto& contacts = contact_buckets_;
  clear_buckets(bonds, K + 1), clear_buckets(contacts, K + 1);
  if (!spheres_.empty() && !acting) {
    auto t = timers_.scope("contact_list");
    update_list(dt_);
  }
  {
    auto t = timers_.scope("contact_forces");
    for (std::size_t b = 0; b < block_.bonds.size(); ++b) {
      const std::size_t i = static_cast<std::size_t>(block_.bonds[b].master), j = static_cast<std::size_t>(block_.bonds[b].slave);
      if (broken_[b] || (owner_[i] != rank && owner_[j] != rank)) continue;
      bonds[static_cast<std::size_t>(std::max(level_[i], level_[j]))].push_back(static_cast<int>(b));
    }
    for (std::size_t p = 0; p < pairs_.size(); ++p) {
      const std::size_t a = static_cast<std::size_t>(pairs_[p].ea), b = static_cast<std::size_t>(pairs_[p].eb);
      contacts[static_cast<std::size_t>(std::max(level_[a], level_[b]))].push_back(static_cast<int>(p));
    }
  }
  // The hole's faces of my elements by their element's level, in the hole's order (an element's
  // faces keep their order: its sums take the same bits).
  clear_buckets(hole_buckets_, K + 1);
  for (int sf : hole_faces_) {
    const std::size_t e = static_cast<std::size_t>(block_.surface[static_cast<std::size_t>(sf)].element);
    if (owner_[e] == rank) hole_buckets_[static_cast<std::size_t>(level_[e])].push_back(sf);
  }
  // Immediate impulses (stability levels): an element is kicked whenever one of its pairs is
  // evaluated, so it is updated at its finest pair's level; every rank learns these levels (one
  // reduction per macro step) and with them which states travel at each sub-step.
  const bool immediate = settings_.stepping == Stepping::stability;
  const bool skip = immediate && settings_.skip_apart;  // B7a: every pair read at states drifted to t
  std::vector<int>& kick_level = kick_level_;
  kick_level = level_;
  if (immediate) {
    for (std::size_t b = 0; b < block_.bonds.size(); ++b) {
      if (broken_[b]) continue;
      const std::size_t i = static_cast<std::size_t>(block_.bonds[b].master), j = static_cast<std::size_t>(block_.bonds[b].slave);
      const int k = std::max(level_[i], level_[j]);
      kick_level[i] = std::max(kick_level[i], k), kick_level[j] = std::max(kick_level[j], k);
    }
    for (const ListedPair& lp : pairs_) {
      const std::size_t i = static_cast<std::size_t>(lp.ea), j = static_cast<std::size_t>(lp.eb);
      const int k = std::max(level_[i], level_[j]);
      kick_level[i] = std::max(kick_level[i], k), kick_level[j] = std::max(kick_level[j], k);
    }
    if (P > 1) MPI_Allreduce(MPI_IN_PLACE, kick_level.data(), static_cast<int>(kick_level.size()), MPI_INT, MPI_MAX, decomp_.comm());
  }
  // Elements by owner and the level at which they are updated (every rank builds the same table).
  auto& by_level = element_buckets_;
  by_level.resize(static_cast<std::size_t>(P));
  for (auto& levels : by_level) clear_buckets(levels, K + 1);
  for (std::size_t e = 0; e < block_.size(); ++e)
    by_level[static_cast<std::size_t>(owner_[e])][static_cast<std::size_t>(kick_level[e])].push_back(static_cast<int>(e));

  // Immediate impulses read each pair at its elements' states at t: a sub-step first drifts to t every
  // element a rank reads, its own due elements and the other ranks' elements its pairs touch (these
  // from the state their owner sent, as their owner drifts them: the same bits), then evaluates the
  // pairs, then kicks its own; only those states travel between the sub-steps (build_halo).
  if (immediate && P > 1)
    build_halo(K);
  else
    clear_buckets(halo_.in, K + 1);

  const long substeps = 1L << K;
  const double h_min = dt_ / static_cast<double>(substeps);
  min_dt_ = std::min(min_dt_, h_min);
  if (h_min <= min_dt_) min_dt_time_ = time_;
  newly_broken_.clear();
  std::vector<std::vector<int>>& due = due_;  // each rank's elements due at a sub-step (storage kept)
  due.resize(static_cast<std::size_t>(P));
  for (long s = 0; s < substeps; ++s) {
    const double t = time_ + static_cast<double>(s) * h_min;
    const int first = s == 0 ? 0 : K - std::countr_zero(static_cast<unsigned long>(s));
    if (immediate) {
      auto timer = timers_.scope("kick_drift");
      for (int k = first; k <= K; ++k) {
        advance_all(by_level[static_cast<std::size_t>(rank)][static_cast<std::size_t>(k)], t);
        advance_all(halo_.in[static_cast<std::size_t>(k)], t);
      }
    }
    {
      auto timer = timers_.scope("bond_forces");
      for (int k = first; k <= K; ++k) {
        const double h = std::ldexp(dt_, -k);
        const std::vector<int>& due_bonds = bonds[static_cast<std::size_t>(k)];
        for (std::size_t n = 0; n < due_bonds.size(); ++n) {
          const int b = due_bonds[n];
          // The due bonds are scattered over the bond arrays: ask for a later one's lines now.
          if (n + kPrefetchAhead < due_bonds.size()) prefetch_bond(static_cast<std::size_t>(due_bonds[n + kPrefetchAhead]));
          if (broken_[static_cast<std::size_t>(b)]) continue;
          const BondGeometry& g = block_.bonds[static_cast<std::size_t>(b)];
          const std::size_t i = static_cast<std::size_t>(g.master), j = static_cast<std::size_t>(g.slave);
          ++bond_evaluations_;
          const PairForce f = bond_force(static_cast<std::size_t>(b), pose_at(i, t), pose_at(j, t));
          if (owner_[j] == rank) S_[j] += f.force * h, A_[j] += f.torque_j * h;
          if (owner_[i] == rank) S_[i] -= f.force * h, A_[i] += f.torque_i * h;
          if (f.failed) {
            broken_[static_cast<std::size_t>(b)] = 1;  // at once here; everywhere at the macro step's end
            if (owner_[i] == rank) newly_broken_.push_back(b);
          }
        }
      }
    }
    {
      auto timer = timers_.scope("contact_forces");
      for (int k = first; k <= K; ++k) {
        const double h = std::ldexp(dt_, -k);
        const std::vector<int>& due = contacts[static_cast<std::size_t>(k)];
        // B7a first, on every due pair (its force is zero where it cannot touch), then the pairs
        // that may touch: their spheres are scattered (their loads were half of a pair's time) and
        // are asked for ahead among the pairs evaluated, not among those skipped.
        std::vector<int>& due_pairs = skip ? touching_ : contacts[static_cast<std::size_t>(k)];
        if (skip) {
          touching_.clear();
          for (std::size_t n = 0; n < due.size(); ++n) {
            if (n + kPrefetchAhead < due.size()) __builtin_prefetch(&pairs_[static_cast<std::size_t>(due[n + kPrefetchAhead])]);
            const ListedPair& pair = pairs_[static_cast<std::size_t>(due[n])];
            if (may_touch(pair, static_cast<std::size_t>(pair.ea), static_cast<std::size_t>(pair.eb))) touching_.push_back(due[n]);
          }
        }
        for (std::size_t n = 0; n < due_pairs.size(); ++n) {
          if (n + kPrefetchAhead < due_pairs.size()) prefetch_pair(static_cast<std::size_t>(due_pairs[n + kPrefetchAhead]));
          const int p = due_pairs[n];
          ListedPair& pair = pairs_[static_cast<std::size_t>(p)];
          const std::size_t a = static_cast<std::size_t>(pair.ea), b = static_cast<std::size_t>(pair.eb);
          ++contact_evaluations_;
          const PairForce f = contact_force(static_cast<std::size_t>(p), pose_at(a, t), pose_at(b, t), h);
          if (skip) note_gap(pair, a, b, f.gap);
          // Most evaluated pairs are apart: a zero force (and torque) adds nothing to the sums (an
          // added +-0 leaves every sum's bits), so their scattered sums are not touched.
          if (f.force.x == 0 && f.force.y == 0 && f.force.z == 0) continue;
          if (owner_[a] == rank) S_[a] += f.force * h, A_[a] += f.torque_j * h;
          if (owner_[b] == rank) S_[b] -= f.force * h, A_[b] += f.torque_i * h;
        }
      }
    }
    {
      auto timer = timers_.scope("borehole");
      if (hole_) {
        const double pressure = hole_->pressure(t);
        for (int k = first; k <= K && pressure != 0; ++k)
          for (int sf : hole_buckets_[static_cast<std::size_t>(k)]) {
            const std::size_t e = static_cast<std::size_t>(block_.surface[static_cast<std::size_t>(sf)].element);
            Vec3 F, T;
            if (!hole_load(sf, pressure, F, T)) continue;
            const double h = std::ldexp(dt_, -k);
            S_[e] += F * h, A_[e] += T * h;
          }
      }
    }
    {
      auto timer = timers_.scope("kick_drift");
      for (int k = first; k <= K; ++k) {
        const double h = std::ldexp(dt_, -k);
        for (int e : by_level[static_cast<std::size_t>(rank)][static_cast<std::size_t>(k)]) {
          const std::size_t i = static_cast<std::size_t>(e);
          if (immediate) {
            kick_impulse(i);  // drifted to now before the pairs; kicked with what arrived now
          } else {
            kick_impulse(i);  // eq. 3: the impulses of the step that ends now, then the next drift
            advance_to(i, t + h);
            t_el_[i] = time_ + static_cast<double>(s + (1L << (K - k))) * h_min;  // as t is formed
          }
          ++element_steps_;
        }
      }
    }
    if (P > 1 && immediate) {
      auto timer = timers_.scope("exchange");
      exchange_halo(first, K);
    } else if (P > 1) {
      auto timer = timers_.scope("exchange");
      for (int r = 0; r < P; ++r) {
        auto& d = due[static_cast<std::size_t>(r)];
        d.clear();
        for (int k = first; k <= K; ++k)
          d.insert(d.end(), by_level[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)].begin(),
                   by_level[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)].end());
      }
      exchange_elements(due);
    }
  }
  time_ += dt_;
  ++steps_;
  if (immediate) {
    // Everyone drifts to the macro step's end and the states travel once more.
    advance_all(owned_by_rank_[static_cast<std::size_t>(rank)], time_);
    std::fill(t_el_.begin(), t_el_.end(), time_);
    if (P > 1) exchange_elements(owned_by_rank_);
    if (acting && steps_ % settings_.damping_interval == 0) {
      // B9a: the bond dashpots over the macro step, all together, at the states of its end; the
      // velocities they change travel again.
      {
        auto t = timers_.scope("damping");
        damp_bonds(settings_.damping_interval * dt_);
      }
      if (P > 1) exchange_elements(owned_by_rank_);
    }
  }
  // Every element is at the macro step's end: all clocks agree again (no rounding drift).
  std::fill(t_el_.begin(), t_el_.end(), time_);
  auto timer = timers_.scope("broken");
  share_broken();
}

}  // namespace tessera
