// SPDX-License-Identifier: MIT
// The bodies as the flow sees them (theory C1-C5): each body's tetrahedra, at its current position
// and orientation, laid exactly over the grid cells (tet_clip.hpp).
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
//   correct_velocity()   the cell velocity becomes the mass average of the fluid in the cell and the
//                        solid in it (C4): u = (rho_f V_f u + sum_b rho_b V_bc u_b) / (rho_f V_f + m_s).
//
// Every body that overlaps a rank's cells is there, owned or as a ghost: the DEM copies a body to a
// neighbour when its centre is within r + r_max + skin of the face, and the constructor checks that
// the tetrahedra and half a cell fit in that reach. Each cell is summed by its one owner rank over
// the bodies in canonical order, so alpha_s has the same bits on any rank count.
#pragma once
#include <cstdint>
#include <vector>

#include "coupling/tet_clip.hpp"
#include "fluid/flow_solver.hpp"
#include "solid/dem_solver.hpp"

namespace tessera {

struct SolidPhaseStats {
  double solid_volume = 0;  // sum of alpha_s V_c over the grid (collective)
  double body_volume = 0;   // sum of the bodies' tetrahedra volumes (owned bodies, collective)
  double max_fraction = 0;  // largest alpha_s (above 1 where bodies overlap at contacts)
  double free_liquid_volume = 0;  // sum f (1 - min(alpha_s, 1)) V_c: the liquid outside the bodies
  long covered_cells = 0;
};

class SolidPhase {
 public:
  // Checks that the coupling can run: bodies made of tetrahedra (shape templates), none lighter than
  // kMinDensityRatio times `fluid_density` (the denser fluid's), no periodic flow boundary, and the
  // tetrahedra plus half a cell within the DEM's ghost reach.
  SolidPhase(const FluidGrid& grid, const DemSolver& dem, double fluid_density);
  static constexpr double kMinDensityRatio = 0.3;

  void update(const DemSolver& dem);
  void fluid_loads(const FlowSolver& flow, DemSolver& dem);
  void exchange_momentum(const FlowSolver& flow, DemSolver& dem);
  void correct_velocity(FlowSolver& flow) const;

  // Ghosted layout of the grid (owned cells set, ghosts exchanged).
  const std::vector<double>& fraction() const { return alpha_; }
  SolidPhaseStats stats(const FlowSolver& flow) const;  // collective

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
  void solid_momentum(const DemSolver& dem);  // m_s and P_s per cell from the bodies' velocities now
  TetRasterizer raster_;
  std::vector<std::pair<std::size_t, double>> scratch_;
};

}  // namespace tessera
