// SPDX-License-Identifier: MIT
// Bonded tetrahedra that fracture (the blast seed; docs/theory.md B1-B9). One step is the ordered
// list of stages below; timers use the same names.
//
//   kick_drift      owned elements: v += dt/2 F/m, L += dt/2 T; x += dt v; free rotation (T9)
//   exchange        every rank gets every element's x, q, v, w (replicated state, section below)
//   bond_forces     intact bonds touching an owned element (B2-B5), in bond order
//   contact_forces  contact spheres of broken faces and of the block's surface (B6-B7), between
//                   elements not bonded to each other: list rebuilt when faces break or a sphere
//                   moved more than skin/2; pairs in key order; a pair that cannot touch yet
//                   is skipped (B7a)
//   borehole        the gas pressure P(t) on the hole's faces (B8) of fragments not free in the gas (B8a)
//   kick            v += dt/2 F/m, L += dt/2 T
//   broken          faces released this step are made known to every rank
//
// Parallel (the seed's own scheme, section 3.2): every rank holds every element's state; an element
// belongs to one rank (settings.partition: element_partition.hpp), which integrates it. A bond or a contact is evaluated by each rank owning one of
// its two elements (a pair across ranks twice, with the same inputs and so the same bits), and an
// element sums its forces in bond order, then contact order, then the hole: the results do not
// depend on the rank count. The states travel by one all-gather per step (uniform steps, travel
// levels, and the stability levels' macro step), and between the stability levels' sub-steps only
// to the ranks whose pairs read them (the halo: build_halo, exchange_halo).
#pragma once
#include <mpi.h>

#include <map>
#include <optional>
#include <vector>

#include "core/decomposition.hpp"
#include "core/timers.hpp"
#include "fracture/bond_law.hpp"
#include "fracture/bonded_block.hpp"
#include "fracture/element_partition.hpp"
#include "fracture/face_spheres.hpp"
#include "fracture/sphere_grid.hpp"
#include "fracture/fragments.hpp"

namespace tessera {

// Storage of the all-gathers of element states (every sub-step with levels), reused.
struct GatherBuffers {
  std::vector<int> counts, displs;
  std::vector<double> mine, all;
};

// The borehole's gas pressure (seed eq. 4, B8): a cos^2 rise over a, a cosine fall over b a.
struct Borehole {
  Vec3 centre{};             // a point on the axis
  Vec3 axis{0, 0, 1};        // unit
  double radius = 0.025;
  double p0 = 5.75e8, rise = 1.33e-4, fall = 2.75;  // P0, a, b
  double pressure(double t) const;
};

// Time integration (B9, B10): one step for all elements (velocity Verlet), or per-element levels
// dt0 / 2^k with shared impulses, chosen by the seed's travel limit or by each element's stability.
enum class Stepping { uniform, travel, stability };

struct FractureSettings {
  double density = 2390;
  BondLaw bond;
  double contact_stiffness = 1.5e9;  // post-fracture sphere contacts (B7), N/m
  double contact_damping = 3.08e6;   // N s/m
  double contact_friction = 0.58;    // sliding friction only
  int sphere_divisions = 5;          // each broken face's edges divided in 5 (Fig. 5)
  std::optional<double> time_step;   // none: stability_factor * the smallest element period (B9)
  double stability_factor = 0.2;
  Stepping stepping = Stepping::uniform;
  double travel_limit = 1e-8;        // l: |v| dt <= l (travel levels)
  int max_level = 30;
  bool damping = true;               // false: no dashpots (energy tests)
  bool implicit_damping = false;     // B9a: the bond dashpots all together, backward Euler
  double damping_rtol = 1e-3;        // B9a: the solve's residual over its right-hand side (the change)
  double damping_theta = 0.5;        // B9a: 1/2 the trapezoidal rule, 1 backward Euler
  double damping_frozen_angle = 1e-4;  // B9b: an element's frozen orientation follows it past this turn
  int damping_interval = 1;  // B9c: the dashpots solved every this many macro steps, over as many
                                       // (rad; or a tenth of its stiffest dashpot mode's margin)
  bool skip_apart = true;            // B7a: pairs that cannot touch are not evaluated (false: tests)
  bool relax_born_overlaps = true;   // B7b: a pair listed at a release starts from its overlap then
  Partition partition = Partition::slabs;  // which rank owns each element (element_partition.hpp)
};

// A pair's force: on the second element (the slave; contact: sphere a's element) `force`, on the
// first minus it; the torques about each element's centroid.
struct PairForce {
  Vec3 force{}, torque_j{}, torque_i{};
  bool failed = false;  // bonds: a vertex reached u_f
  double gap = 0;       // contacts: the spheres' gap (negative: the overlap)
};

// What rebuilds the contact list after a restart exactly as it was: the element poses at its last
// build, or stale = true (rebuild at the next step).
struct ContactListState {
  std::vector<Vec3> x;
  std::vector<Quaternion> q;
  bool stale = true;
  std::vector<std::pair<long, long>> pairs;  // every listed pair (all ranks), by sphere key
  std::vector<int> unlisted;                 // faces released since the list was last made, in order
  double cell_radius = 0;                    // the largest sphere radius at the last build
  std::vector<std::pair<std::pair<long, long>, double>> sunk;  // B7b: pairs born overlapping, by key
  long born_overlaps = 0;       // B7b's counts so far (summary.json)
  double deepest_born_overlap = 0;
};

struct FractureEnergies {
  double kinetic = 0, bond_elastic = 0, contact_elastic = 0;
};

class FractureSolver {
 public:
  FractureSolver(const Decomposition& decomp, BondedBlock block, FractureSettings settings,
                 std::optional<Borehole> hole);

  // Call once before stepping. fresh: the forces of the initial state; false (after restore): the
  // checkpoint's forces, so that a restart repeats the interrupted run bit for bit.
  void setup(bool fresh = true);
  void step();

  double time() const { return time_; }
  long steps() const { return steps_; }
  double dt() const { return dt_; }  // the step (per-element levels: the macro step dt0)
  const std::vector<int>& levels() const { return level_; }  // per-element levels of the last macro step
  double min_dt() const { return min_dt_; }                   // the smallest sub-step so far, and when
  double min_dt_time() const { return min_dt_time_; }
  void set_clock(double t, long steps) { time_ = t, steps_ = steps; }
  const BondedBlock& block() const { return block_; }
  const FractureSettings& settings() const { return settings_; }
  const std::optional<Borehole>& borehole() const { return hole_; }
  const std::vector<int>& hole_faces() const { return hole_faces_; }  // indices into block().surface
  // The bonded fragments now (B8a), and how many hole faces the gas no longer pushes: those of
  // fragments lighter than the rock the hole took out (hole_mass).
  const Fragments& fragments() const { return fragments_; }
  double hole_mass() const { return hole_mass_; }
  long unloaded_hole_faces() const;
  PhaseTimers& timers() { return timers_; }
  const Decomposition& decomposition() const { return decomp_; }

  // Element state (every rank holds all; x, q, v, w current everywhere after a step's exchange,
  // velocities of the full step on the owner only until sync_state()).
  const std::vector<Vec3>& x() const { return x_; }
  const std::vector<Vec3>& v() const { return v_; }
  const std::vector<Vec3>& w() const { return w_; }
  const std::vector<Quaternion>& q() const { return q_; }
  const std::vector<int>& owner() const { return owner_; }
  // The work a macro step gives each rank on the partition in use (element_partition.hpp: updates
  // and bond evaluations at the levels it was made from, the start's unless the run rebalanced;
  // a cut bond on both of its ranks), and the bonds cut.
  std::vector<double> planned_work() const { return part_work(block_, work_, owner_, decomp_.size()); }
  long cut_bond_count() const { return cut_bonds(block_, owner_); }
  // The same per sub-step kind: row f is the work when the levels f and finer are due.
  std::vector<std::vector<double>> planned_level_work() const {
    return part_level_work(block_, work_, owner_, decomp_.size());
  }
  const ElementWork& work() const { return work_; }
  // Collective, between macro steps (issue 19): the work now (the last macro step's levels, the
  // intact bonds, the listed contact pairs, gathered once) and its sub-steps' imbalance
  // (substep_imbalance) on the owners now; and a new partition of that check's work, the state
  // carried over as a restart carries it (the same bits as without), returning the new owners'
  // imbalance.
  struct BalanceCheck {
    ContactListState list;
    ElementWork work;
    double imbalance = 1.0;
  };
  BalanceCheck balance_check() const;
  // The levels a macro step would take from the state now (after restore and setup: `tessera
  // balance` pricing a checkpoint's work).
  void take_levels() { assign_levels(); }
  double rebalance(const BalanceCheck& check);
  bool owns(std::size_t e) const { return owner_[e] == decomp_.rank(); }
  // Collective: every rank takes the owners' full state of elements and bonds (before output).
  void sync_state();
  // Sets an element's velocity (every rank alike; initial conditions and tests).
  void set_velocity(std::size_t e, const Vec3& v, const Vec3& w);

  const std::vector<std::array<BondVertex, 3>>& bond_state() const { return bond_state_; }
  const std::vector<char>& broken() const { return broken_; }
  long broken_count() const;
  // Collective. Restart: the full state (every rank passes the same arrays).
  void restore(const std::vector<Vec3>& x, const std::vector<Quaternion>& q, const std::vector<Vec3>& v,
               const std::vector<Vec3>& L, const std::vector<std::array<BondVertex, 3>>& bonds,
               const std::vector<char>& broken, const ContactListState& list, const std::vector<Vec3>& F,
               const std::vector<Vec3>& T);
  const std::vector<Vec3>& torque() const { return T_; }
  ContactListState contact_list_state() const;  // collective
  // B9b: each element's frozen orientation, from its owner (collective); restart: every rank passes
  // the same array (a checkpoint without one: the elements' orientations).
  std::vector<Quaternion> damping_frozen() const;
  void set_damping_frozen(const std::vector<Quaternion>& q) { frozen_q_ = q; }
  const std::vector<Vec3>& angular_momentum() const { return L_; }

  FractureEnergies energies() const;  // collective; bond energy of the elastic law (B2)
  long contact_evaluations() const { return contact_evaluations_; }  // this rank, sphere pairs in range
  long bond_evaluations() const { return bond_evaluations_; }
  long element_steps() const { return element_steps_; }  // this rank
  long damping_iterations() const { return damping_iterations_; }  // B9a's solves' CG iterations so far
  long damping_solves() const { return damping_solves_; }
  long list_builds() const { return list_builds_; }
  long list_refreshes() const { return list_refreshes_; }  // searches of the stale elements only
  // B7b: pairs listed overlapping at a release so far, the deepest such overlap, and the pairs that
  // still have a sunk depth (collective, every rank's once).
  long born_overlaps() const;
  double deepest_born_overlap() const;
  std::size_t sunk_pairs() const;
  std::size_t sphere_count() const { return spheres_.size(); }
  std::size_t pair_count() const { return pairs_.size(); }
  // Each element's force at the last evaluation (uniform stepping; current on its owner).
  const std::vector<Vec3>& force() const { return F_; }

 private:
  // An element's state where a pair is evaluated, with its rotation matrix (rows); the uniform step
  // builds it once per element and step however many pairs read it.
  struct Pose {
    Vec3 x, v, w;
    Quaternion q;
    std::array<Vec3, 3> R;
    Vec3 rot(const Vec3& a) const { return {dot(R[0], a), dot(R[1], a), dot(R[2], a)}; }
    Vec3 unrot(const Vec3& a) const { return R[0] * a.x + R[1] * a.y + R[2] * a.z; }  // world -> body
  };
  // Inline: the sub-steps build two for every pair they evaluate.
  static Pose make_pose(const Vec3& x, const Vec3& v, const Vec3& w, const Quaternion& q) {
    const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z, xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z,
                 wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    return {x, v, w, q,
            {Vec3{1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)}, Vec3{2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)},
             Vec3{2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)}}};
  }
  struct Sphere {
    int element;
    Vec3 centre;  // body frame
    double radius;
    long key;  // (bond, side, k)
  };
  void kick(double h);
  void drift();
  void exchange();
  void exchange_elements(const std::vector<std::vector<int>>& lists);  // each list's rank's states to all
  // An element's state as it travels: x, q, v, then w (uniform steps) or L (levels: w = spin(L) on
  // arrival, as on the owner), then its clock.
  static constexpr int kStateWidth = 14;
  void pack_state(std::size_t i, bool momentum, double* o) const;
  void unpack_state(std::size_t i, bool momentum, const double* s);
  double element_limit(std::size_t e) const;
  // B9a: the stable step of the springs that act now: the intact bonds, and `pairs` contact pairs
  // that may touch whose levers' squares (r x n per principal axis, body frame) sum to `levers`.
  double acting_limit(std::size_t e, double pairs, const Vec3& levers) const;
  int level_for(double limit) const;  // the smallest k with dt0 / 2^k <= limit (at most max_level)
  void choose_steps();  // dt_ and, with stability levels, each element's level (B9, B10)
  // On its piecewise-linear path (B10); at its own clock (every read with stability levels), inline.
  Pose pose_at(std::size_t e, double t) const {
    return t == t_el_[e] ? make_pose(x_[e], v_[e], w_[e], q_[e]) : pose_ahead(e, t);
  }
  Pose pose_ahead(std::size_t e, double t) const;
  void assign_levels();
  void advance_to(std::size_t e, double t);  // drift (x, q) from its clock to t
  void advance_all(const std::vector<int>& elements, double t);  // advance_to on each, interleaved
  template <int W>
  void drift(const int* e, double t);  // W elements that move, from their clocks to t, at once
  static constexpr int kBatch = 4;     // elements drifted together (free_rotation_steps)
  void prefetch_bond(std::size_t b) const;  // a cache hint: the bond's geometry and state
  void prefetch_pair(std::size_t p) const;  // a cache hint: the pair's two spheres
  // B7a: adds to travel_[e] how far any point of element e can have moved since its state
  // (x, q) was (x_old, q_old): the centroid's move and its farthest vertex's chord.
  void add_travel(std::size_t e, const Vec3& x_old, const Quaternion& q_old) {
    const Quaternion d = q_[e] * Quaternion{q_old.w, -q_old.x, -q_old.y, -q_old.z};
    travel_[e] += norm(x_[e] - x_old) + 2 * reach_[e] * std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  }
  void kick_impulse(std::size_t e);          // v += S / m, L += A
  // The world angular velocity of element e at its orientation, from its body-frame momentum.
  Vec3 spin(std::size_t e, const Vec3& L_body) const {
    const Vec3& I = block_.inertia[e];
    return q_[e].rotate({L_body.x / I.x, L_body.y / I.y, L_body.z / I.z});
  }
  void multirate_step();
  void damp_bonds(double h);  // B9a: the bond dashpots over h, all bonds together (fracture_damping.cpp)
  void damping_links(double h);   // its stages: the intact bonds here, their units now, who travels
  void damping_matrix(double h);  // M + theta h C at the frozen orientations, scaled (B9b)
  void damping_solve();           // the right-hand side, CG, the impulses
  void damping_share(std::vector<double>& V, std::size_t width);  // the partners' entries, from their owners
  void build_halo(int K);               // the cross pairs' elements by rank and level (every macro step)
  void exchange_halo(int first, int K);  // the due ones' states, to and from the neighbour ranks
  static void clear_buckets(std::vector<std::vector<int>>& buckets, int count);  // at least count, all empty
  void compute_forces(double t);  // t: the time of the state (the hole's pressure)
  const Pose& pose(std::size_t e);  // the current state (cached until new_epoch())
  void new_epoch() { ++epoch_; }
  // B2-B5 on bond b (updates its state); B7 on contact pair p over the pair's step h (its dashpot
  // and friction are backward Euler over h).
  PairForce bond_force(std::size_t b, const Pose& master, const Pose& slave);
  PairForce contact_force(std::size_t p, const Pose& a, const Pose& b, double h);
  void bond_forces();
  void contact_forces();
  void borehole_forces(double t);
  // B8, B8a: the gas's force on hole face s at pressure p and its torque about the element's
  // centroid; false (none) when the face's fragment is free in the gas.
  bool hole_load(int s, double p, Vec3& F, Vec3& T) const;
  void share_broken();
  void update_fragments();  // fragments_ and hole_loaded_ from broken_
  void add_spheres(int bond);
  void add_surface_spheres();
  // Marks stale_ the elements whose spheres may come within reach of one not listed before
  // `horizon` has passed (moved_: each element's travel since it was last searched); returns how many.
  int mark_stale(double horizon);
  // Two elements still joined by an intact bond: their spheres do not touch (the bond carries it).
  bool bonded(int a, int b) const;
  void build_list();
  void extend_list();               // the spheres and unbonded pairs of faces released since
  void refresh_list();              // the stale elements' pairs searched again
  void update_list(double horizon);  // extend, refresh or rebuild, valid for the coming `horizon`
  // Lists the pair if within reach + margin; `born`: listed because a face was released (B7b).
  void consider_pair(int a, int b, const Vec3& pa, const Vec3& pb, double margin = 0, bool born = false);
  // B7b: the pairs of two elements whose bond is in unlisted_bonds_ or with a sphere not yet listed.
  bool born_at_release(int a, int b) const;
  std::vector<std::pair<std::pair<long, long>, double>> all_sunk() const;  // collective, by key
  void sort_pairs(std::size_t sorted = 0);  // the first `sorted` pairs are in order already
  void count_pairs();  // collective: listed_pairs_ of every element
  // The list's cells (sphere_grid.hpp): every sphere where its element was last searched (build_x_,
  // build_q_); spheres up to 1.5 times the largest at the last build (the faces released until the
  // next one); every search padded by 2 skins (a refresh's margin of skin/2 beyond the skin, and a
  // sphere may be skin/2 from where the grid holds it).
  // Two grids: the spheres of this rank's elements and the others'. A pair is listed where one of
  // its elements is owned, so a search from another rank's sphere reads only this rank's grid.
  void reset_grid();
  bool mine(std::size_t sphere) const { return owner_[static_cast<std::size_t>(spheres_[sphere].element)] == decomp_.rank(); }
  SphereGrid& grid_of(std::size_t s) { return grids_[mine(s) ? 0 : 1]; }
  void insert_sphere(std::size_t s, const Vec3& p) { grid_of(s).insert(static_cast<int>(s), p, spheres_[s].radius); }
  // f(b) for every sphere b within reach of sphere a at p that a pair listed here can have (a search
  // of both grids from this rank's spheres, of this rank's grid from the others'); see SphereGrid::near.
  template <class F>
  void near_sphere(std::size_t a, const Vec3& p, bool coarser_only, F&& f) const {
    grids_[0].near(p, spheres_[a].radius, coarser_only, f);
    if (mine(a)) grids_[1].near(p, spheres_[a].radius, coarser_only, f);
  }
  Vec3 sphere_position(std::size_t s) const;
  double stable_dt() const;
  void assign_owners();  // owner_ and owned_by_rank_ from a partition of work_ (collective)
  ElementWork work_now(const ContactListState& list) const;

  const Decomposition& decomp_;
  BondedBlock block_;
  FractureSettings settings_;
  std::optional<Borehole> hole_;
  std::vector<int> hole_faces_;
  double hole_mass_ = 0;           // density x the hole's volume (B8a)
  Fragments fragments_;
  std::vector<char> hole_loaded_;  // per element: its fragment holds the gas (B8a)
  std::vector<int> owner_;
  ElementWork work_;
  std::vector<std::vector<int>> element_bonds_;  // bonds of each element
  std::vector<std::vector<int>> owned_by_rank_;
  std::vector<Vec3> x_, v_, w_, L_, F_, T_;
  std::vector<Quaternion> q_;
  std::vector<std::array<BondVertex, 3>> bond_state_;
  std::vector<char> broken_;
  std::vector<int> newly_broken_;  // this step, bonds whose master this rank owns
  std::vector<Sphere> spheres_;
  // A listed pair of spheres (first's key < second's) and, for B7a, the travel sum of its two
  // elements below which it cannot touch (-inf: evaluate it); kept with the pair as the list changes.
  // B7b: `sunk`, the overlap the pair may have without force (the depth it was born with at a
  // release, shrinking as it opens; 0 for almost every pair).
  struct ListedPair {
    int first = 0, second = 0;
    int ea = 0, eb = 0;  // first's and second's elements (the sub-steps' loops read them per visit)
    double budget = -1e300;
    double sunk = 0;
  };
  ListedPair listed_pair(int first, int second) const {
    return {first, second, spheres_[static_cast<std::size_t>(first)].element, spheres_[static_cast<std::size_t>(second)].element};
  }
  std::vector<ListedPair> pairs_;
  std::vector<std::vector<int>> hole_buckets_;  // my hole faces by their element's level (a macro step)
  std::vector<int> touching_;  // a sub-step's due pairs that may touch (B7a), storage kept
  // B7b: a pair's sunk depth went to `depth` (0: an ordinary pair again), on every rank that holds it.
  void set_sunk(ListedPair& p, double depth);
  // B7b's depths as the evaluations leave them: a listed pair's `sunk` only falls, and the map
  // below takes the listed pairs' depths (keep_sunk) before the list changes or is read by key,
  // not at each evaluation. opened_: the pairs (indices in pairs_) whose depth reached 0 since.
  void keep_sunk();
  std::map<std::pair<long, long>, double> current_sunk() const;
  std::vector<std::size_t> opened_;
  // B7a: a pair whose elements have not together travelled the gap it had when last evaluated
  // cannot touch (its force is zero: skipping it gives the same bits); note_gap records that gap.
  bool may_touch(const ListedPair& p, std::size_t a, std::size_t b) const { return travel_[a] + travel_[b] >= p.budget; }
  void note_gap(ListedPair& p, std::size_t a, std::size_t b, double gap) const {
    p.budget = gap > kGapMargin ? travel_[a] + travel_[b] + gap - kGapMargin : -1e300;
  }
  std::vector<int> listed_pairs_;  // per element: its listed pairs (every rank alike; B7's split)
  // B7b: the pairs with a sunk depth, by sphere keys (the list's pairs come and go; this stays).
  std::map<std::pair<long, long>, double> sunk_;
  long born_overlaps_ = 0;       // pairs born overlapping so far (this rank)
  double deepest_born_ = 0;      // the deepest of them, m
  std::vector<Vec3> build_x_;
  std::vector<Quaternion> build_q_;
  double max_radius_ = 0, skin_ = 0;
  std::vector<double> reach_;  // each element's farthest vertex from its centroid
  // Per element and local face: the largest lever |e_a x r|^2 about each principal axis, and the area.
  std::vector<std::array<std::array<double, 4>, 4>> face_k_;
  std::vector<double> b9_limit_;  // B9a's levels: each element's B9 limit, the finest they take
  std::vector<double> moved_;  // each element's travel since its spheres were last searched
  // B7a (stability levels): each element's travel so far, a bound summed over every change of its
  // pose on this rank (the pairs' budgets are in pairs_).
  std::vector<double> travel_;
  static constexpr double kGapMargin = 1e-12;  // m: far above the round-off of positions near 1 m
  std::vector<char> stale_;
  // Storage reused every macro step: mark_stale's speeds and partners' fastest, build_list's positions.
  std::vector<double> scratch_speed_, scratch_fastest_;
  std::vector<double> scratch_pairs_;  // B9a: each element's listed pairs that may touch
  std::vector<Vec3> scratch_levers_;   // B9a: and their levers' squares about its principal axes
  std::vector<Vec3> scratch_at_;
  GatherBuffers gather_;
  std::vector<std::vector<int>> due_;  // the multirate step's due elements per rank
  std::vector<std::vector<int>> element_spheres_;
  std::vector<int> unlisted_bonds_;  // released since the list was last made
  std::size_t listed_spheres_ = 0;
  SphereGrid grids_[2];  // [0]: this rank's elements' spheres, [1]: the other ranks'
  double cell_radius_ = 0;  // the largest sphere at the last build
  double dt_ = 0, time_ = 0, min_dt_ = 1e300, min_dt_time_ = 0;
  std::vector<int> level_, stable_level_, kick_level_;
  // Per-level lists of the macro step (bonds, contact pairs; elements by owner), storage reused.
  std::vector<std::vector<int>> bond_buckets_, contact_buckets_;
  std::vector<std::vector<std::vector<int>>> element_buckets_;
  // Stability levels: what travels between sub-steps (build_halo, exchange_halo).
  struct HaloLists {
    std::vector<std::vector<int>> in;                 // other ranks' elements my pairs read, by level
    std::vector<std::vector<std::vector<int>>> out;   // [rank][level]: my elements its pairs read
    std::vector<std::vector<std::vector<int>>> from;  // [rank][level]: its elements my pairs read
    std::vector<int> neighbours;                      // ranks with either, ascending
    std::vector<std::array<int, 2>> sent, read;       // (rank, my element) and (rank, its element)
    std::vector<std::vector<double>> send, recv;      // per neighbour, storage kept
    std::vector<MPI_Request> requests;
  };
  static constexpr int kHaloTag = 1717;
  HaloLists halo_;
  std::vector<Pose> pose_cache_;
  std::vector<long> pose_epoch_;
  long epoch_ = 0;
  std::vector<double> t_el_;      // each element's clock (its x, q are of that time)
  std::vector<Vec3> S_, A_;       // impulse and angular impulse since its last update
  long damping_iterations_ = 0, damping_solves_ = 0;
  // B9a's solve (fracture_damping.cpp): storage kept between calls.
  using Block6 = std::array<double, 36>;
  using Block6f = std::array<float, 36>;
  struct DampingUnit {  // one bond vertex: the master face's normal, the levers, h (A/3) c_n and c_s
    Vec3 n, ri, rj;
    double an, at;
  };
  struct DampingLink {  // one intact bond with an element here
    int bond, i, j;
    int slot;  // its kept blocks (DampingWork)
    bool own_i, own_j;
  };
  using Lower6 = std::array<double, 21>;  // a symmetric 6 x 6 block's lower triangle, by rows
  struct DampingWork {
    std::vector<DampingUnit> units;  // three per link, at the elements' orientations now
    std::vector<DampingLink> links;
    // B9b: the matrix at the frozen orientations, kept between calls. A bond with an element here
    // has a slot (in bond order, from the first call); per slot its terms in its master's and slave's
    // diagonal blocks, its off-diagonal block and that block scaled, L_i^-1 B L_j^-T, in single
    // precision; live while it is intact and built.
    std::vector<int> slot;  // per bond, -1: none
    std::vector<char> live;
    std::vector<Lower6> to_i, to_j;
    std::vector<Block6> off;
    std::vector<Block6f> off_f;
    double h = 0;                    // the step the kept blocks are for (0: none yet)
    std::vector<Pose> frozen;        // per element: its pose at its frozen orientation (R only)
    std::vector<char> turned;        // per element, this call: its frozen orientation moved
    std::vector<char> remade;        // per element, this call: its diagonal block (and L^-1) remade
    std::vector<char> link_remade;   // per link, this call: its blocks remade
    std::vector<Block6> diag;        // per element (owned): its diagonal block (lower triangle read)
    std::vector<double> linv;        // per element: its diagonal block's L^-1 (21 lower entries by rows)
    std::vector<double> x, b, r, p, ap;
    std::vector<double> v0;           // theta < 1: the velocities before
    std::vector<std::array<int, 2>> sent, read;
    std::vector<int> neighbours;
    std::vector<std::vector<int>> send_elements, recv_elements;
    std::vector<std::vector<double>> send, recv;
    std::vector<MPI_Request> requests;
  };
  DampingWork damping_;
  std::vector<Quaternion> frozen_q_;  // B9b: per element, the orientation its damping blocks are made at
  std::vector<double> frozen_cos_;  // B9b: per element, cos(angle / 2) of the turn past which it follows
  static constexpr int kDampingTag = 1718;
  static constexpr std::size_t kTri = 21;  // a 6 x 6 lower triangle's entries
  static constexpr int kMaxDampingIterations = 1000;
  long steps_ = 0, contact_evaluations_ = 0, bond_evaluations_ = 0, element_steps_ = 0, list_builds_ = 0,
       list_refreshes_ = 0;
  PhaseTimers timers_;
};

}  // namespace tessera
