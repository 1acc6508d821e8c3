// SPDX-License-Identifier: MIT
// Geometric multigrid for the cell-centred pressure operator (docs/theory.md F9a), used as the
// preconditioner of CG (a PETSc PCSHELL).
//
// The operator on every level is the 7-point flux form (A x)_c = sum_f c_f (x_c - x_nb) + e_c x_c
// with face coefficients c_f = A_f / (h_f rho_f) and e_c the outflow (p = 0) terms. A coarse cell
// aggregates the fine cells of one rank's block in pairs along each direction that can be coarsened;
// a block of odd length ends in a single cell, so odd sizes coarsen too (180 -> 90 -> 45 -> 23 ->
// 12 -> 6; ending in a triple instead took 13-14 CG iterations where pairs take 10,
// test_cell_multigrid), and on the coarser levels that cell, once narrower than the one before it,
// joins the pair before it (no slivers; multigrid_plan.hpp). A direction is not coarsened (semi-coarsening) where it is shorter than 4
// cells, or, periodic, where a block or the whole is odd (red-black colouring needs even periodic
// lengths and uniform pairs there); where a rank's block would fall below 2 cells on several
// ranks, the coarser level is gathered onto half the ranks along that direction (below). A coarse face coefficient is the sum of the fine
// coefficients across it times the fine centres' distance across it over the coarse centres', both
// in finest cells (at a domain face, the distances to the face: the outflow term's; theory F9a,
// coarse_face_distance). Fine residuals are summed into the coarse cell (the rows are cell integrals),
// corrections are injected back (the transpose): with red-black Gauss-Seidel smoothing, forward
// before and reversed after the coarse correction, the V-cycle is a symmetric positive
// (semi-)definite preconditioner, as CG needs. The V-cycle reads its coefficients in single
// precision (the smoother streams them: 4 bytes a face instead of 8; theory F9a): rounded once,
// they are one fixed symmetric operator per level, so the cycle stays a fixed symmetric
// preconditioner; the operator CG iterates on (apply_operator) keeps the double coefficients. Red-black sweeps give the same numbers on any rank
// count (the aggregates, and so the preconditioner, follow the ranks' blocks). With level_pairs
// (`fluid.poisson.multigrid.pairs: level`) the cells are paired over each whole level that is not
// gathered, pairs across a cut included (owned by the rank of their first cell: the residuals and
// coefficients of the neighbour's first cells come in one exchange, the pair's correction goes back
// in another): the aggregates, and so the V-cycle's numbers, are one rank's wherever no level is
// gathered.
//
// Each level's blocks are each rank's aggregates; their ghosts are filled by fluid/cell_halo.hpp,
// two layers deep where every split block is at least 2 cells across and every face at most 2,048
// cells (latency-bound exchanges), so that a red-black sweep needs one exchange instead of two
// (theory F9a), else one. Where a direction's blocks would fall below
// 2 cells on several ranks, the coarser level is gathered: pairs of ranks along that direction
// hand their aggregates to the first of the pair, which owns both parts from there down (the
// others wait for its correction), so every direction coarsens on as on one rank (theory F9a).
// Coarsening stops where no direction can be coarsened or below 256 cells; the coarsest level is
// solved exactly (or by 20 sweeps). The levels' sizes, blocks, gathers and ghost layers come from
// fluid/multigrid_plan.hpp, which lays them out from the finest level's cuts alone.
#pragma once
#include <petscdmda.h>
#include <petscksp.h>

#include <array>
#include <initializer_list>
#include <memory>
#include <vector>

#include "fluid/fluid_grid.hpp"
#include "fluid/cell_halo.hpp"
#include "fluid/multigrid_plan.hpp"

namespace tessera {

// The levels another process grid would make, laid out on one process (issue 19): its blocks along
// each direction from `cuts` (interior planes; where empty, a flow run's default: cell_block_cuts, else
// equal slabs), planned as on those ranks (aggregates, triples, gathers), then held whole by the one
// process. The V-cycle's numbers depend only on the aggregates (red-black passes by global parity,
// restriction and prolongation within aggregates, the coarsest level by LU in natural order), so the
// iterations are those ranks' (test CellMultigrid.LevelsLaidOutAsOnAnotherGridTakeItsIterations).
// grid {0, 0, 0}: the run's own blocks.
struct LevelsAsOn {
  std::array<int, 3> grid{0, 0, 0};
  std::array<std::vector<double>, 3> cuts;
  bool any() const { return grid[0] > 0; }
};

class CellMultigrid {
 public:
  // coarse_direct: the coarsest level solved exactly (LU, every rank a copy); else coarse_sweeps.
  // ghost_layers: 2 lets a smoothing sweep's two passes follow one exchange on the levels whose
  // split blocks are at least 2 cells across and whose faces are small (the others keep 1 layer
  // and an exchange per pass); 1 everywhere exchanges before every pass. The same numbers either
  // way.
  // level_pairs: the cells paired over each whole level where it is not gathered (one rank's
  // aggregates on any cuts: the V-cycle's numbers those of one rank), else within each rank's block.
  CellMultigrid(const FluidGrid& grid, int pre_sweeps = 2, int post_sweeps = 2, int coarse_sweeps = 20,
                bool coarse_direct = true, int ghost_layers = 2, const LevelsAsOn& as_on = {},
                bool level_pairs = false);
  ~CellMultigrid();
  CellMultigrid(const CellMultigrid&) = delete;
  CellMultigrid& operator=(const CellMultigrid&) = delete;

  // Face coefficients of the finest level from the cell densities (field layout of `grid`,
  // ghosts valid); and, when `coarse`, the coarse levels.
  void set_coefficients(const std::vector<double>& rho, bool coarse = true);
  // y = M^-1 x for PETSc vectors on the pressure DMDA (one V-cycle from a zero guess).
  void apply(Vec x, Vec y);
  // y = A x with the finest level's coefficients: the operator itself, matrix-free (the same
  // coefficients pressure_poisson.cpp assembles for PETSc preconditioners).
  void apply_operator(Vec x, Vec y);
  int levels() const { return int(levels_.size()); }
  long coarsest_cells() const;
  int gathered_levels() const;  // levels gathered onto fewer ranks than the next finer one
  int two_layer_levels() const;  // levels whose ghosts are two layers deep (one exchange a sweep)
  // Ghost exchanges per V-cycle on this rank, the operator's own (one a Krylov iteration) counted
  // in: what the scaling model prices per cycle (0 before the first cycle).
  double exchanges_per_cycle() const { return cycles_ ? double(exchanges_) / double(cycles_) : 0.0; }
  double exchange_seconds() const { return exchange_seconds_; }  // ghost exchanges, all levels
  CellHalo::Traffic halo_traffic() const;                          // what they sent, all levels

 private:
  struct Level {
    // The ranks that own cells of this level (a rank left out of a gathered level is left out of
    // every coarser one): their communicator (MPI_COMM_NULL elsewhere), process grid, and this
    // rank's coordinates in it.
    bool active = true;
    MPI_Comm comm = MPI_COMM_NULL;
    std::array<int, 3> procs{}, coords{};
    // Gathered from the next finer level: each of its ranks computes its part (the aggregates of
    // its block) and sends it to the part's owner here. On a finer rank, its part and the owner's
    // rank (on the multigrid's own communicator); on an owner, the parts it holds.
    struct Part {
      int rank = 0;
      std::array<int, 3> s{}, m{};
    };
    bool gathered = false;
    Part part;
    std::vector<Part> parts;
    std::vector<double> staging;                // this rank's part of a transfer
    std::vector<std::vector<double>> inbox;     // an owner's parts of a transfer
    std::vector<MPI_Request> requests;          // an owner's transfers in flight
    // Ghost layers (theory F9a): 1, face ghosts, an exchange before every red-black pass; or 2,
    // edges and corners too, the first layer's cells updated like owned ones after an exchange,
    // so that a sweep's two passes need one exchange.
    int layers = 1;
    std::unique_ptr<CellHalo> halo;
    // With 2 layers, the face coefficients' exchange: the owned box reaches the high domain faces
    // along the unsplit directions, so the ghost cells get their boundary faces too.
    std::unique_ptr<CellHalo> face_halo;
    // Aggregates across a cut (multigrid_plan.hpp's crosses; fluid.poisson.multigrid.pairs: level):
    // on the finer level, the residuals' one-layer exchange (edges and corners too) and its face
    // coefficients' (the owned box reaching the high domain faces); on the coarser, its
    // correction's and its coefficients' (an owner's high face is its neighbour's low one). The
    // residuals of the owned cells of the pre-smoothing's first colour, the other colour 0.
    bool crosses = false;
    std::unique_ptr<CellHalo> cross_halo, cross_coef_halo;
    std::vector<double> r;
    CellHalo::Block block;  // this rank's block of the level (the halos')
    std::array<int, 3> n{}, s{}, m{}, gs{}, gm{};
    std::array<std::ptrdiff_t, 3> stride{};
    // Along each direction, the first cell of the next finer level's aggregate I, global,
    // I = 0..n (the last entry is the finer level's size); empty on the finest level.
    std::array<std::vector<int>, 3> fine_start;
    int width(int d, int I) const { return fine_start[d][I + 1] - fine_start[d][I]; }
    // Along each direction, the aggregate I of each cell i of the next finer level (global).
    std::array<std::vector<int>, 3> aggregate_of;
    // The V-cycle's operator: the face on the low side of each cell, and the smoother's inverse
    // diagonal (1 for a zero row, an isolated cell); single precision (theory F9a).
    std::array<std::vector<float>, 3> coef;
    std::vector<float> inv_diag;
    std::vector<double> x, b;
    // Finest level only: the operator's face coefficients in double (apply_operator).
    std::array<std::vector<double>, 3> op_coef;
    std::size_t at(int i, int j, int k) const {
      return (std::size_t(k - gs[2]) * gm[1] + std::size_t(j - gs[1])) * gm[0] + std::size_t(i - gs[0]);
    }
  };
  void exchange(Level& L, std::initializer_list<std::vector<double>*> fields);
  // An exchange on one of a level's halos (exchange(): its smoothing halo), counted among the
  // cycle's exchanges and timed.
  void exchange_on(const std::unique_ptr<CellHalo>& halo, std::initializer_list<std::vector<double>*> fields);
  // The smoother's inverse diagonal of the owned cells; with 2 layers first the ghost cells' face
  // coefficients from their owners, and the first ghost layer's too (the same bits as its owner's).
  void set_inverse_diagonal(Level& L);
  // Red-black sweeps, all passes in one stream down the level, each a plane behind the one before,
  // the cells beside exchanged ghosts after an exchange per pass, or with 2 ghost layers per two
  // passes (theory F9a). `from_zero`: x starts at 0 (its first pass reads no neighbour); else the
  // ghosts are exchanged first. `ghosts_after`: the first ghost layer holds the last pass's
  // values at the end (the residual reads it).
  void smooth(Level& L, int sweeps, bool reverse, bool from_zero, bool ghosts_after);
  // The residual b - A x of level l, summed into the next coarser level's b (restriction).
  void restrict_residual(Level& L, Level& C);
  // The coarser level's correction added to each of its aggregate's cells (prolongation).
  void prolong(Level& C, Level& L);
  // A gathered level's transfers: every finer rank's part (`mine`, `size(part)` values) to the
  // part's owner, which reads each through unpack(part, values); and back, each owner's parts
  // packed by pack(part, values) to their ranks, which receive theirs into `mine`.
  template <class Size, class Unpack>
  void gather(Level& C, const std::vector<double>& mine, Size&& size, Unpack&& unpack);
  template <class Pack>
  void scatter(Level& C, std::vector<double>& mine, Pack&& pack);
  void cycle(std::size_t l);
  // The coarsest level's exact solve (theory F9a; cell_multigrid_coarsest.cpp): its operator (the V-cycle's single-precision
  // coefficients, in double) gathered to every rank in the level's natural order and factored by
  // LU there, the right-hand side gathered the same way: the same arithmetic on any rank count.
  void assemble_coarsest();
  void solve_coarsest();
  // Every rank's block of the coarsest level (s, m per direction), and a gathered field in the
  // blocks' order, to natural order.
  std::vector<int> coarse_blocks_, coarse_counts_, coarse_displs_;
  std::vector<double> coarse_mine_, coarse_all_;
  template <class F>
  void for_natural(F&& fn) const;  // fn(natural index, index in coarse_all_), block by block

  const FluidGrid& grid_;
  int pre_, post_, coarse_;
  int ghost_layers_;
  bool coarse_direct_;
  Mat coarse_A_ = nullptr;
  KSP coarse_ksp_ = nullptr;
  Vec coarse_b_ = nullptr, coarse_x_ = nullptr;
  double exchange_seconds_ = 0;
  long exchanges_ = 0, cycles_ = 0;
  MPI_Comm transfer_comm_ = MPI_COMM_NULL;     // the gathered levels' transfers
  std::vector<MPI_Comm> level_comms_;          // the gathered levels' communicators
  CellHalo::Traffic transfer_traffic_;
  std::vector<std::unique_ptr<Level>> levels_;
  std::vector<MultigridLevelPlan> plan_;  // the levels' lay-out (sizes, blocks, widths)
};

}  // namespace tessera
