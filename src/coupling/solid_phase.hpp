// SPDX-License-Identifier: MIT
// The bodies as the flow sees them (theory C1-C5): each body's tetrahedra (or, for a convex body,
// the polytope its surface bounds), at its current position and orientation, laid exactly over the
// grid cells (tet_clip.hpp).
//
//   update()             per local body (owned and ghost, in canonical order), the volume V_bc it
//                        shares with each owned cell c; the solid fraction alpha_s = sum_b V_bc / V_c
//                        (C1), and per cell the solid mass sum_b rho_b V_bc and momentum
//                        sum_b rho_b V_bc (v_b + w_b x (x_c - x_b)) (C2).
//   fluid_loads()        the fluid force and moment on each body (C3):
//                        F_b = sum_c V_bc (-grad p + div tau)_c, T_b = sum_c V_bc (x_c - x_b) x (...),
//                        over this rank's cells, then the ghost copies' shares sent back to the owner
//                        (Halo::reverse_add); written to the bodies' external loads.
//   exchange_momentum()  the no-slip exchange between each body and the fluid in its cells, implicit
//                        (C4a): the body's velocity and spin after the exchange solve one 6 x 6
//                        system; the fluid loses exactly what the body gains.
//   held_exchange()      for bodies held at rest (`coupling.bodies: fixed`): C4a with the body's
//                        velocity kept at 0, i.e. the momentum C4 takes from the fluid in the body's
//                        cells, sum_c mu_c u_c (and sum_c mu_c r_c x u_c), added over dt to the
//                        body's reported load (C3 + C4b): the whole force of the flow on it.
//   correct_velocity()   the cell velocity moves towards the solid's: a cell the bodies cover takes
//                        their velocity; a partly covered one relaxes towards it at a rate that does
//                        not depend on the step (C4c, `PartialCells`), or, as the seed does, takes the
//                        mass average of its fluid and solid every step (C4).
//
// Every body that overlaps a rank's cells is there, owned or as a ghost: the DEM copies a body to a
// neighbour when its centre is within r + r_max + skin of the face, and the constructor checks that
// the tetrahedra and half a cell fit in that reach. Each cell is summed by its one owner rank over
// the bodies in canonical order, so alpha_s has the same bits on any rank count.
#pragma once
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "coupling/pore_liquid.hpp"
#include "coupling/tet_clip.hpp"
#include "fluid/flow_solver.hpp"
#include "solid/dem_solver.hpp"
#include "solid/rigid_rotation.hpp"
#include "solid/shape.hpp"

namespace tessera {

// Lays one body out over `cells` (theory C1): fn(i, j, k, volume) per cell it shares volume with.
// world: the shape's nodes at the body's pose. A convex shape is swept whole (one piece per cell),
// any other tetrahedron by tetrahedron (a cell may then be reported once per tetrahedron).
template <class F>
void lay_out_body(const ShapeTemplate& shape, const std::vector<Vec3>& world, const CellRange& cells,
                  CellRasterizer& raster, Polytope& scratch, F&& fn) {
  if (shape.convex) {
    scratch.set_triangles(world, shape.surface);
    raster.overlaps(scratch, cells, fn);
    return;
  }
  for (const auto& tet : shape.tetrahedra)
    raster.overlaps(Tet{world[tet[0]], world[tet[1]], world[tet[2]], world[tet[3]]}, cells, fn);
}

// How the correction treats a cell the bodies cover in part (theory C4c).
struct PartialCells {
  // `step` (the seed's MICS, the default): every flow step the cell takes the mass average of its
  // fluid and its solid, u <- (m_f u + P_s) / (m_f + m_s): the flow a partly covered cell lets through
  // then scales with the step and with the solid's density. `rate`: the cell is pulled towards the
  // solid's velocity U = P_s / m_s at the rate lambda = kappa nu alpha_s / ((1 - alpha_s) h^2), a
  // drag implicit in the flow's projection (FlowSolver's CellDrag) up to lambda dt = kMaxDrag, the
  // rest of it by the correction: u <- (u + lambda dt U) / (1 + lambda dt) in all.
  bool per_step = true;
  // kappa: chosen on the cubic sphere array of docs/validation.md (c = 0.216, 12 and 16 cells per
  // spacing); theory C4c.
  double rate = 25;
  // c_E: the rate is times 1 + c_E |u - U| h / nu, the slip's inertia; Ergun's ratio of inertial to
  // viscous coefficients by default (theory C4c); 0: viscous only.
  double inertia = 1.75 / 150;
};

struct SolidPhaseStats {
  double solid_volume = 0;  // sum of alpha_s V_c over the grid (collective)
  double body_volume = 0;   // sum of the bodies' tetrahedra volumes (owned bodies, collective)
  double max_fraction = 0;  // largest alpha_s (above 1 where bodies overlap at contacts)
  long covered_cells = 0;
};

class SolidPhase {
 public:
  // Checks that the coupling can run: bodies made of tetrahedra (shape templates), none lighter than
  // kMinDensityRatio times `fluid_density` (the denser fluid's), no periodic flow boundary, and the
  // tetrahedra plus half a cell within the DEM's ghost reach.
  // layout_tolerance (a fraction of the smallest cell side; 0: exact): a body is laid out at its pose
  // rounded to that step (and its orientation to quaternion components of a power of 2 that moves
  // no node of its shape by more than the step), and its lay-out is reused while that rounded pose is
  // unchanged: a bed at rest is laid out once. The solid volume stays exact; every node of the body
  // sits in the grid within (1 + sqrt(3)/2) steps of its place (theory C1).
  SolidPhase(const FluidGrid& grid, const DemSolver& dem, double fluid_density, double layout_tolerance = 0,
             PartialCells partial = {});
  static constexpr double kMinDensityRatio = 0.3;

  void update(const DemSolver& dem);
  // Before a flow step dt (`rate`): each partly covered cell's drag towards the bodies' velocity now,
  // for FlowSolver::set_cell_drag; nullptr with the seed's correction.
  const CellDrag* drag(const FlowSolver& flow, const DemSolver& dem, double dt);
  static constexpr double kMaxDrag = 100;  // lambda dt in the projection at most (its coefficients)
  // The fluid force and moment (C3; the reaction to C4c's drag comes with the exchange, C4a). With
  // conserve_momentum(true) and the flow keeping its advection change, also that change of the
  // virtual fluid in the body's cells over the flow step dt (theory C8).
  void fluid_loads(const FlowSolver& flow, DemSolver& dem, double dt = 0);
  // On: the two momentum leaks of C8 go to the bodies: the advection's change of their virtual
  // fluid (C3) and the momentum of the fluid their new lay-out takes or gives back (C4a).
  void conserve_momentum(bool on) { conserve_ = on; }
  // dt: the flow step the exchange and the correction stand for (0 at the start: a partly covered
  // cell is left as it is, unless the correction is the seed's per-step one).
  void exchange_momentum(const FlowSolver& flow, DemSolver& dem, double dt);
  void held_exchange(const FlowSolver& flow, DemSolver& dem, double dt);  // after fluid_loads
  void correct_velocity(FlowSolver& flow, const DemSolver& dem, double dt);

  // Ghosted layout of the grid (owned cells set, ghosts exchanged).
  const std::vector<double>& fraction() const { return alpha_; }
  // The bodies laid out again by the last update: per body, the change of the volume it shares with
  // each owned cell (the liquid stage moves the liquid they displaced, C7).
  const BodyMoves& moves() const { return moves_; }
  using Pose = std::array<double, 7>;  // x, y, z, qw, qx, qy, qz
  Pose layout_pose(const Vec3& x, const Quaternion& q, int shape) const;
  long layouts_computed() const { return layouts_; }  // this rank, whole run
  std::size_t cell_entries() const { return cell_.size(); }  // the bodies' cells here, one a body and cell
  // Of those, the bodies whose nodes could not reach this rank's cells (ghosts, mostly): nothing
  // was turned or swept for them.
  long layouts_elsewhere() const { return layouts_elsewhere_; }
  void count_layouts(long earlier, long elsewhere) {  // those of a solid phase this one replaced
    layouts_ += earlier;
    layouts_elsewhere_ += elsewhere;
  }
  SolidPhaseStats stats() const;  // collective

 private:
  const FluidGrid& grid_;
  std::vector<double> alpha_, solid_mass_;
  std::array<std::vector<double>, 3> solid_momentum_;
  // Per local body in canonical order: its index in the particle store, and its cells (CSR).
  std::vector<std::size_t> body_index_, body_first_;
  std::vector<std::size_t> cell_;
  std::vector<double> volume_;
  double body_volume_ = 0;  // owned bodies
  std::vector<double> loads_;  // 6 per local body (reverse communication); 16 in the exchange
  static constexpr int kExchangeWidth = 16;
  void exchange_sums(const FlowSolver& flow, DemSolver& dem, double dt);
  // The share of the way from its velocity to the solid's U = P_s / m_s that cell c goes in the
  // correction over dt (m_f > 0: the cell's fluid mass; m_s: its solid mass).
  double pull(const FlowSolver& flow, std::size_t c, double mf, double ms, double dt) const;
  PartialCells partial_;
  double cell_rate(const FlowSolver& flow, std::size_t c) const;  // lambda, before any cap
  CellDrag drag_;
  double drag_dt_ = 0;  // the step the drag was set for (0: none)
  bool dragged(std::size_t c) const { return drag_dt_ > 0 && drag_.rate[c] > 0; }
  double inv_h2_ = 0, inv_h_ = 0;  // means of 1 / h_d^2 and 1 / h_d over the three directions
  std::vector<double> slip_;  // |u - U| per cell at the step's start (the rate's inertial part)
  void solid_momentum(const DemSolver& dem);  // P_s per cell from the bodies' velocities now
  CellRasterizer raster_;
  Polytope body_polytope_;  // a convex body's surface, in the world
  // Lay-outs by body order key, kept while the body's rounded pose is unchanged.
  using CellVolumes = std::vector<std::pair<std::size_t, double>>;
  struct Layout {
    Pose pose{};
    CellVolumes cells;
    long generation = 0;
    bool valid = false;
  };
  std::unordered_map<std::int64_t, Layout> cache_;
  double layout_step_ = 0;
  std::vector<double> node_reach_;  // per shape: its farthest node from the centre
  std::vector<double> turn_step_;  // per shape (index shape - 1): quaternion components' rounding
  long generation_ = 0, layouts_ = 0, layouts_elsewhere_ = 0;
  std::vector<std::pair<std::size_t, double>> scratch_;
  CellVolumes old_cells_;
  BodyMoves moves_;
  bool conserve_ = false;
  void record_move(std::size_t b, const CellVolumes& before, const CellVolumes& after);
};

}  // namespace tessera
