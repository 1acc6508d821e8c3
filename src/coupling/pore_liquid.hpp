// SPDX-License-Identifier: MIT
// The liquid in the fluid part of each cell (theory C7): the water lives between the bodies, not in
// the virtual fluid that fills them.
//
// Two fields per cell:
//   c    the liquid content, liquid volume over the cell's volume, 0 <= c <= e with e = 1 - min(alpha_s, 1)
//        the cell's fluid part: the conserved quantity (sum c V_c is the liquid volume);
//   phi  the flow's liquid fraction (FlowSolver::fraction), the liquid share of the fluid in the cell,
//        virtual fluid included: it sets the density and viscosity the flow uses and its interface.
//
// Per coupled step:
//   before_flow  keeps phi;
//   after_flow   c += phi_new - phi_old: the liquid that crossed the cell's faces in the flow's
//                advection (the swept volumes are fluid, the bodies held still in the flow step,
//                so the liquid that enters a pore cell fills only its fluid part and a front in a
//                bed of porosity e advances at u / e);
//   displace     after the bodies moved: each moved body takes the liquid out of the volume it
//                entered (at the cell's liquid share) and puts it, all of it, into the volume it left,
//                in proportion to the volume left in each cell: a body moving through water leaves
//                water behind it, one moving from air into water pushes water out and leaves air
//                behind it. The body's sums go to its owner and back to its ghost copies. Exact in
//                liquid, and every cell stays within [0, e] if it was before.
//   settle       what is still out of [0, e] (the flow carried liquid into a body's cells: the flow
//                step moves the virtual fluid too; round-off; cells where bodies overlap) fills the
//                neighbouring cells' room and passes on with the flow, a negative content is filled
//                from neighbours with liquid and from upstream, in Jacobi passes (conservative, the
//                same bits on any rank count), until no cell is out of [0, e] by more than
//                kTolerance; then phi = c / e where e >= e_min,
//                blended towards the advected phi where the fluid part is smaller (the virtual fluid
//                of a body's inside takes its surroundings' liquid share).
//
// In cells without bodies (e = 1) c and phi are the same number and the stage changes nothing: the
// flow's VOF there is the plain scheme of F4-F7.
#pragma once
#include <array>
#include <functional>
#include <vector>

#include "fluid/flow_solver.hpp"

namespace tessera {

// Per moved body, the change of the volume it shares with each owned cell (SolidPhase::update).
struct BodyMoves {
  std::vector<std::size_t> body;   // the body's local index (the communication's slot)
  std::vector<std::size_t> first{0};  // its entries: [first[n], first[n + 1])
  std::vector<std::size_t> cell;
  std::vector<double> dv;           // V_bc new - old (m^3)
  void clear() { body.clear(), first.assign(1, 0), cell.clear(), dv.clear(); }
};

struct PoreLiquidStats {
  int passes = 0;            // Jacobi passes of the last settle
  double residual = 0;       // largest |c - clamp(c, 0, e)| left after it (fractions of a cell)
  double displaced = 0;      // liquid volume moved by it (m^3, collective sum of |excess| at the start)
};

class PoreLiquid {
 public:
  static constexpr double kMinFluidPart = 0.1;   // e_min: below it phi blends with the advected value
  // Largest excess settle leaves (fraction of a cell), and its passes per step: what is left stays
  // where it is (conserved; reported as the residual and as liquid_in_bodies) for the next step.
  static constexpr double kTolerance = 1e-6;
  static constexpr int kMaxPasses = 20;

  explicit PoreLiquid(const FluidGrid& grid);

  // A fresh start: c = phi e (the liquid initially in a body's cells is its virtual fluid, not liquid).
  void start(const FlowSolver& flow, const std::vector<double>& alpha);
  // A restart: the liquid content was read (mutable_content); `alpha` is the solid fraction it was
  // settled with (the bodies' moves are measured from it).
  void resume(const std::vector<double>& alpha) { alpha_old_ = alpha; }
  void before_flow(const FlowSolver& flow);
  void after_flow(const FlowSolver& flow);
  // Collective. Displaces the liquid into the fluid part of the cells for solid fraction `alpha`
  // (ghosted) and sets the flow's liquid fraction from it.
  PoreLiquidStats settle(FlowSolver& flow, const std::vector<double>& alpha);
  // Collective. The liquid the moved bodies displaced (before settle, with the new alpha). `complete`
  // turns each moved body's 2 partial sums per slot (values[2 * slot], slot = BodyMoves::body) into
  // the sums over every rank, on every rank holding the body (the DEM's reverse and forward ghost
  // communication; a test's single body: an all-reduce); `slots` is the values' length / 2.
  void displace(const BodyMoves& moves, std::size_t slots,
                const std::function<void(std::vector<double>&)>& complete);

  // Ghosted layout of the flow's grid (owned cells meaningful).
  const std::vector<double>& content() const { return c_; }
  std::vector<double>& mutable_content() { return c_; }  // restart
  double volume() const;  // collective: sum c V_c over the grid
  // Collective: sum max(c - e, 0) V_c, liquid still inside the bodies' volume (0 to the tolerance).
  double volume_in_bodies(const std::vector<double>& alpha) const;
  const PoreLiquidStats& last() const { return last_; }
  struct Box;  // a box of cells (pore_liquid.cpp)

 private:
  const FluidGrid& grid_;
  std::vector<double> c_, phi_old_, excess_, share_, share2_, alpha_old_, entered_, sums_, next_;
  std::vector<unsigned char> mode_;
  std::array<std::vector<double>, 3> uf_;  // the flow's face speeds, ghost faces exchanged
  PoreLiquidStats last_;
  // One Jacobi pass: every cell above e (sign +1) or below 0 (-1) hands its excess to its face
  // neighbours in the domain
  // (`active`: the box of those cells).
  void pass(const std::vector<double>& alpha, const Box& active, int sign);
};

}  // namespace tessera
