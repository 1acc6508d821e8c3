// SPDX-License-Identifier: MIT
// The DEM: one time step (step()) is the ordered list of stages below; timers use the names in
// brackets. Each contact stage is a class that owns its lists, springs and coefficients:
//
//   first_half_kick_and_drift  [integrate]  v += dt/2 (F/m + g), w += dt/2 T/I, x += dt v,
//                              q += dt/2 (0,w) q (T8); free spheres and pivot meshes alike
//                              (dem_integrator.cpp); shaped bodies' elements placed, meshes moved
//   update_neighbours          [neighbor, migration, ghost_comm]  if some body moved > skin/2 since
//                              the last build (global check): migrate -> ghosts -> order -> pair
//                              list and every stage's list; otherwise refresh the ghosts. With
//                              relisting (shaped bodies), the global check counts only bodies near
//                              a cut, and the others' stale pairs are listed again on their rank
//   compute_forces             [contact_forces] pairs (PairContacts, T1-T4, canonical order)
//                              [wall_forces] planes and boxes (PlaneWallContacts, T7), mesh walls
//                              (MeshWallContacts, T14), free spheres (FreeSphereContacts, T17);
//                              all into the contact buffer of ContactEntities
//   second_half_kick           [integrate]  v += dt/2 (F/m + g), w += dt/2 T/I (T8); step(true)
//                              defers it into the next first pass, which then applies both kicks
//
// Velocity Verlet (LAMMPS nve/sphere), second order for conservative forces; the damping and
// history terms see the half-step velocity.
//
// Shaped bodies (shape templates, T13): when the case declares templates, contacts are between
// contact elements (a sphere body is one element; a shaped body has one per contact sphere, placed
// at x + R(q) c_s each step, moving with v + w x R(q) c_s; contact_entities.hpp). The list, the
// kernel and the histories work on elements; each contact's force goes to its two bodies with its
// lever-arm torque, in the canonical pair order. Shaped bodies rotate by the DLM splitting (T9)
// between the torque half-kicks; spheres keep the update above.
#pragma once
#include <mpi.h>

#include <array>
#include <optional>
#include <unordered_map>
#include <vector>

#include "core/balance.hpp"
#include "core/config.hpp"
#include "core/decomposition.hpp"
#include "core/exact_sum.hpp"
#include "core/timers.hpp"
#include "solid/coefficient_table.hpp"
#include "solid/contact_entities.hpp"
#include "solid/contact_history.hpp"
#include "solid/contact_kernel.hpp"
#include "solid/contact_model.hpp"
#include "solid/free_sphere_contacts.hpp"
#include "solid/halo.hpp"
#include "solid/mesh_wall_contacts.hpp"
#include "solid/pair_contacts.hpp"
#include "solid/particles.hpp"
#include "solid/plane_wall_contacts.hpp"
#include "solid/replicated_loads.hpp"
#include "solid/rigid_rotation.hpp"
#include "solid/shape.hpp"
#include "solid/walls.hpp"

namespace tessera {

struct DemSettings {
  Vec3 gravity{0, 0, -9.81};
  std::optional<double> time_step;  // none: from the contact duration (T6)
  double steps_per_contact = 30;    // dt = t_contact / steps_per_contact when automatic
  double impact_velocity = 1.0;     // reference speed for the Hertz contact duration
  std::optional<double> skin;       // none: 0.5 r_min
  // Shaped bodies without moving walls or free spheres: a body that has moved skin/2 since its own
  // last listing has its pairs listed again alone, and the whole list is rebuilt (with migration and
  // ghosts) only when such a body comes near a cut (`solid.neighbor_relist`, theory T5a).
  bool relist = true;
  // Plane (2D) mode (T15): bodies are discs of `plane_thickness` moving in the plane through
  // `plane_position` normal to axis `plane_normal` (-1: 3D), turning about that axis only.
  int plane_normal = -1;
  double plane_thickness = 0;
  std::optional<double> plane_position;  // none: the middle of the domain along the normal

  static DemSettings from_config(const ConfigNode& solid);
};

struct DemStats {
  long bodies = 0;
  double kinetic_translational = 0, kinetic_rotational = 0;  // bodies and free spheres
  double max_speed = 0;
  long contacts = 0;             // touching element pairs (bodies; contact spheres of shaped bodies)
  long body_contacts = 0;        // touching body pairs (one per pair however many spheres touch)
  long wall_contacts = 0;        // touching element-wall pairs
  long cross_rank_contacts = 0;  // touching element pairs whose bodies have different owners
  double max_overlap_ratio = 0;  // largest overlap over the smaller radius (walls: the body's)
  std::int64_t max_overlap_body = -1;
  bool finite = true;  // every position and velocity finite
};

class DemSolver {
 public:
  DemSolver(const Decomposition& decomp, ContactModel model, Walls walls, DemSettings settings);
  DemSolver(const DemSolver&) = delete;  // its stages hold references to its body store
  DemSolver& operator=(const DemSolver&) = delete;

  ParticleStore& particles() { return p_; }
  // Plane mode: the discs' orientations (q) are brought up to date at each list rebuild and by
  // complete_step(), which writers of q (snapshots, checkpoints) call first.
  const ParticleStore& particles() const { return p_; }
  const ContactModel& model() const { return model_; }
  const Walls& walls() const { return walls_; }
  Walls& walls() { return walls_; }
  const Decomposition& decomposition() const { return decomp_; }
  PhaseTimers& timers() { return timers_; }

  // Adds a sphere if this rank owns its centre (every rank may call it with the same list).
  // density <= 0: the material's density.
  void add_sphere(std::int64_t id, int material, double radius, const Vec3& x, const Vec3& v, const Vec3& omega = {},
                  double density = 0);
  // Shape templates (shape k >= 1 is templates[k - 1]); call before adding shaped bodies. Every rank
  // must pass the same list.
  void set_shapes(std::vector<ShapeTemplate> templates);
  const std::vector<ShapeTemplate>& shapes() const { return shapes_; }
  bool shaped() const { return !shapes_.empty(); }
  // Adds a body of template `shape` (>= 1) if this rank owns its centre; q maps body to world.
  void add_body(std::int64_t id, int material, int shape, const Vec3& x, const Quaternion& q, const Vec3& v,
                const Vec3& omega = {}, double density = 0);
  // Free spheres (T17, free_spheres.hpp): every rank adds the same ones, before setup. density <= 0:
  // the material's. In plane mode a disc of the plane's thickness, its centre put in the plane.
  void add_free_sphere(const std::string& key, int material, double radius, const Vec3& x, const Vec3& v,
                       const Vec3& omega = {}, double density = 0);
  const std::vector<FreeSphere>& free_spheres() const { return free_.spheres(); }
  std::vector<FreeSphere>& free_spheres() { return free_.spheres(); }  // restart: state set from a checkpoint
  // Springs of free spheres on walls and meshes (the same on every rank; restart).
  const HistoryMap& free_sphere_histories() const { return free_.wall_springs(); }
  void set_free_sphere_histories(HistoryMap h) { free_.set_wall_springs(std::move(h)); }
  // History keys are element keys: body order * key_stride() + sphere index (1 without templates).
  std::int64_t key_stride() const { return key_stride_; }
  // Contact histories to use at the first build (restart).
  void preload_histories(HistoryMap h) { pending_ = std::move(h); }

  // Collective. fresh = true computes the forces of the initial state (histories untouched);
  // false keeps the forces stored in the bodies (restart).
  void setup(bool fresh = true);
  // One step. defer_kick = true (sphere bodies; ignored with shaped ones) leaves the step's second
  // half-kick of the bodies to the next step's first pass, which applies both kicks (the same
  // forces, the same operations: the same bits) in one sweep over the bodies instead of two. Until
  // complete_step() or the next step, the bodies' v and w are those of the half step: a caller
  // that defers calls complete_step() before reading body state (stats() refuses; the snapshot
  // and checkpoint writers call it). The club, the ball and mesh walls are always complete.
  void step(bool defer_kick = false);
  // Applies a deferred half-kick and folds the plane-mode turns into q (both idempotent).
  void complete_step();
  // Applies a deferred half-kick only (idempotent): full-step velocities for statistics read at a
  // wall-clock moment (progress lines). The plane-mode fold of q is left to deterministic moments
  // (rebuilds, output, checks), because when it happens changes q's last bits.
  void complete_kick() { apply_pending_kick(); }

  // Time step, chosen at set-up (T6) or set by a caller (the coupled flow's sub-cycling). Applies
  // a pending half-kick first (it belongs to the old step).
  void set_dt(double dt);
  // Collective: `substeps` steps of dt; ends with full-step velocities and orientations (what a
  // coupled flow reads after its DEM sub-cycles).
  void advance(double dt, int substeps);
  // External loads (ParticleStore::f_ext, t_ext; every rank alike): on, the integrator adds each
  // owned body's f_ext and t_ext to its contact force and torque in both half-kicks. Off (the
  // default), they are not read at all. Change the arrays only when no kick is pending (after
  // advance or complete_step).
  void use_external_loads(bool on);
  bool external_loads() const { return external_loads_; }

  double dt() const { return dt_; }
  double time() const { return time_; }
  long steps() const { return steps_; }
  void set_clock(double time, long steps) { time_ = time, steps_ = steps; }
  double skin() const { return skin_; }
  const Vec3& gravity() const { return settings_.gravity; }
  // Changes gravity from the next step on (a deposition's boosted fall); applies a pending half-kick
  // first (it belongs to the old gravity).
  void set_gravity(const Vec3& g);
  bool plane_mode() const { return settings_.plane_normal >= 0; }
  int plane_normal() const { return settings_.plane_normal; }
  double plane_thickness() const { return settings_.plane_thickness; }
  double contact_duration() const { return t_contact_; }

  DemStats stats() const;  // collective
  // Collective: total force of all bodies on each wall primitive at the last force evaluation,
  // summed exactly (the same bits on any rank count).
  std::vector<Vec3> wall_forces() const { return plane_walls_.loads(walls_, decomp_.comm()); }
  // The impulse the planar walls gave the owned bodies over the steps since track_wall_impulse(true)
  // (N s; collective, summed exactly): per step dt/2 (F_n + F_n+1), as the integrator's two
  // half-kicks apply the wall forces. Free spheres and mesh walls are not counted.
  void track_wall_impulse(bool on) { plane_walls_.track_impulse(on); }
  Vec3 wall_impulse() const { return plane_walls_.impulse(decomp_.comm()); }
  // Contact histories of touching pairs (this rank's list; pairs with an owned body).
  HistoryMap histories() const;
  std::size_t list_builds() const { return pairs_.list().builds; }
  std::size_t list_relists() const { return pairs_.list().relists; }
  // The last binning's elements: those in the list's cells, and the ghosts' left out of them (T5b).
  std::size_t listed_elements() const { return pairs_.list().binned; }
  std::size_t ghost_elements_left_out() const { return pairs_.list().left_out; }
  // The elements the list's searches met over the run (its work counter, NeighborList::tests).
  std::size_t list_tests() const { return pairs_.list().tests; }
  std::size_t pair_count() const { return pairs_.list().size(); }
  // Collective: completes the load on each mesh wall (MeshWall::force, moment) for reporting;
  // pivot meshes have it every step already.
  void sum_mesh_loads() { loads_.sum(decomp_.comm(), walls_.meshes(), free_.spheres()); }
  std::size_t halo_bytes_sent() const { return halo_.bytes_sent(); }  // this rank, whole run
  std::size_t migrations() const { return halo_.migrations(); }       // bodies this rank sent away
  // Ghosts: a body is copied to a neighbour when its centre is within radius + max_radius() + skin()
  // of the face (halo.hpp).
  double max_radius() const { return r_max_; }
  // Collective: `values` holds `width` doubles per local body (owned, then ghosts); each ghost's are
  // added to its owner's (reverse communication, Halo::reverse_add). Valid between two steps.
  void reverse_add_ghosts(std::vector<double>& values, int width) { halo_.reverse_add(values, width); }
  // Owners' values to their ghost copies (Halo::forward_values).
  void forward_to_ghosts(std::vector<double>& values, int width) { halo_.forward_values(values, width); }
  // Load balance (issue 19). The work of each owned body, a count that is the same on every run:
  // 1 plus the listed contact pairs it takes part in (element pairs for shaped bodies).
  std::vector<WorkSample> work() const;
  // Collective, between steps: the decomposition's cut planes moved (Decomposition::set_cuts, every
  // rank alike). The bodies, their contact histories and every stage's list follow: a rebuild whose
  // migration repeats until every body is with its new owner. Results do not change (bit for bit;
  // in plane mode the discs' orientations fold their turns at the rebuild, which moves q's last
  // bits and nothing else).
  void rebalance();
  // The narrowest sub-domain the contacts allow: 2 r_max + skin.
  double contact_reach() const { return 2 * r_max_ + skin_; }
  // Collective: ghosts take their owners' x, v, w (and q) now, after an outside change of owned
  // bodies' velocities between steps (the coupling's momentum exchange).
  void refresh_ghosts() { halo_.forward(p_); }

 private:
  // The stages of step() (see the top of this file).
  void first_half_kick_and_drift();
  void update_neighbours();
  void second_half_kick(bool defer);
  void rebuild();
  bool needs_rebuild();
  // The law enters through the per-pair coefficients and the lane kernel's dispatch.
  void compute_forces(bool update_history);
  // Every stage accumulates into the entities' contact buffer; integrate_second (or store_forces)
  // moves the totals into the bodies' f and torque.
  void store_forces();
  void fill_coefficients();  // the law's coefficients of every contact in the stages' lists
  void integrate_first();
  enum class Bodies { shaped, spheres, discs_x, discs_y, discs_z };  // discs: by their plane's normal
  template <Bodies kBodies, bool kExternal>
  void integrate_first_impl();
  void integrate_second();
  template <bool kExternal>
  void integrate_second_impl();
  void apply_pending_kick();
  bool external_loads_ = false;
  // Mesh walls and free spheres move: their candidates are found again when only they moved far
  // enough (the pair list kept).
  void refresh_moving_candidates();
  void find_moving_candidates();  // mesh and free-sphere candidates, then every coefficient index
  bool refresh_moving_ = false;
  bool migrate_until_settled_ = false;  // rebalance: the migration repeats until every body is home
  void check_subdomain_widths() const;
  std::vector<double> x_moving_build_;  // owned bodies at the last candidate search of moving walls
  // The half-kicks (and the drift) of the free spheres and the pivot meshes (dem_integrator.cpp).
  void kick_free_spheres(bool drift);
  void kick_pivots(bool second);
  void rotate_shaped(std::size_t i, const double* torque, double h, double dt);
  bool anisotropic(int shape) const { return shape > 0 && anisotropic_[shape]; }

  const Decomposition& decomp_;
  ContactModel model_;
  Walls walls_;
  DemSettings settings_;
  double plane_position_ = 0;
  std::array<double, 3> velocity_mask_{1, 1, 1}, spin_mask_{1, 1, 1};
  ParticleStore p_;
  ContactEntities entities_{p_};  // bodies or their contact spheres; kernel mirrors, contact buffer
  // The stages that own their state: walls of planes and boxes, mesh walls, free spheres, and the
  // loads the bodies put on the last two (summed over the ranks in key order).
  PlaneWallContacts plane_walls_;
  MeshWallContacts mesh_walls_;
  FreeSphereContacts free_;
  ReplicatedLoads loads_;
  PairContacts pairs_;
  Halo halo_;
  HistoryMap pending_;
  PhaseTimers timers_;
  std::vector<double> x_build_;
  std::vector<double> inv_mass_, inv_inertia_;  // owned bodies, refreshed at each rebuild
  void fold_turns();
  bool kick_pending_ = false;           // step(true): the second half-kick waits in the contact buffer
  std::vector<double> turn_;            // plane mode: each owned disc's turn about the normal since fold_turns
  double moved2_[2] = {0, 0};           // sphere bodies: squared largest displacements (see needs_rebuild)
  bool owned_mirrors_current_ = false;  // the owned bodies' mirrors packed by integrate_first
  CoefficientTable coefficients_;  // the law's sets of every contact in the stages' lists
  ContactLanes lanes_;               // the kernel's lanes, shared by the stages
  // Shaped mode.
  std::vector<ShapeTemplate> shapes_;
  std::vector<char> anisotropic_;  // per shape id: principal moments differ (DLM rotation)
  std::int64_t key_stride_ = 1;
  std::vector<double> q_build_;     // owned bodies' orientations at the last build (shaped mode)
  // Relisting (DemSettings::relist): every local body's pose at its last listing, the stale marks.
  std::vector<double> x_list_, q_list_;
  std::vector<char> stale_;
  std::vector<double> travel_;  // relist_stale(): each body's travel since its own listing (T13's bound)
  bool relist_due_ = false;     // needs_rebuild(): some rank holds a body past s/2 (T5a: all relist then)
  bool relisting() const;
  ContactElements list_elements();
  double element_r_max_ = 0;  // list_elements()' margin (theory T5b)
  void relist_stale();
  // Relisting: between lists the stages read only the elements of a listed pair or a wall entry,
  // so only those are placed a step (placed_, sorted; the owned ones first); a list places all.
  std::vector<std::int32_t> placed_;
  std::vector<char> placed_mark_;  // find_placed's per-element marks, kept between lists
  std::size_t placed_owned_ = 0;
  bool placing_listed_ = false;
  void place_elements(bool ghosts);
  void find_placed();
  // The most a contact sphere of body i has moved since pose (x0, q0): |dx| + 2 c sin(theta / 2).
  double element_travel(std::size_t i, const double* x0, const double* q0) const;
  std::vector<double> arm_;         // per shape: the farthest contact-sphere centre from the body's
  std::vector<double> inertia3_;    // owned bodies: principal moments (3 each)
  double dt_ = 0, time_ = 0, skin_ = 0, r_max_ = 0, t_contact_ = 0;
  long steps_ = 0;
};

}  // namespace tessera
