// SPDX-License-Identifier: MIT
#include "fluid/cell_multigrid.hpp"

#include <algorithm>

#include "core/balance.hpp"
#include "core/errors.hpp"
#include "fluid/cell_multigrid_detail.hpp"
#include "fluid/multigrid_plan.hpp"
#include "fluid/petsc_check.hpp"

namespace tessera {
namespace {

using multigrid_detail::coefficient_sum;
using multigrid_detail::for_owned;

constexpr auto check = petsc_check;


// Walks level L's owned rows in storage order: each row's first owned cell in the ghosted array,
// and its first entry in a PETSc vector of the owned cells (x fastest).
template <class Level, class F>
void for_rows(const Level& L, F&& fn) {
  std::size_t n = 0;
  for (int k = L.s[2]; k < L.s[2] + L.m[2]; ++k)
    for (int j = L.s[1]; j < L.s[1] + L.m[1]; ++j, n += std::size_t(L.m[0])) fn(L.at(L.s[0], j, k), n);
}

// The V-cycle's residual b - A x of cell c: A with the single-precision coefficients and the
// smoother's own diagonal, 1 / inv_diag (0 for a zero row), so that the reversed sweeps after the
// coarse correction are the transpose of those before it and the cycle stays symmetric.
template <class Level>
double residual(const Level& L, std::size_t c) {
  const double diag = coefficient_sum(L, c) > 0 ? 1 / double(L.inv_diag[c]) : 0.0;
  double ax = diag * L.x[c];
  for (int d = 0; d < 3; ++d) {
    const std::ptrdiff_t st = L.stride[d];
    ax -= double(L.coef[d][c]) * L.x[c - st] + double(L.coef[d][c + st]) * L.x[c + st];
  }
  return L.b[c] - ax;
}

// A box of cells [s, s + m) stored x fastest: a level's ghosted array, or a rank's part of a
// gathered level.
struct Box {
  std::array<int, 3> s{}, m{};
  std::size_t at(int i, int j, int k) const {
    return (std::size_t(k - s[2]) * m[1] + std::size_t(j - s[1])) * m[0] + std::size_t(i - s[0]);
  }
  std::size_t size() const { return std::size_t(m[0]) * m[1] * m[2]; }
};

std::array<std::vector<int>, 3> blocks_as_on(const FluidGrid& grid, const LevelsAsOn& as) {
  const std::string key = "fluid.poisson.multigrid.levels_as_on";
  if (grid.size() > 1)
    throw InputError(key, "", "a run on one process (it lays out another process grid's levels there; here " +
                                  std::to_string(grid.size()) + " ranks)");
  std::array<std::vector<int>, 3> blocks;
  for (int d = 0; d < 3; ++d) {
    const int p = as.grid[d], n = grid.cells()[d];
    const double lo = grid.lo()[d], h = grid.h(d), hi = lo + n * h;
    std::vector<double> cuts = as.cuts[d];
    if (cuts.empty() && p > 1) cuts = flow_default_cuts(lo, hi, n, p);  // a flow run's (scene_flow.cpp)
    const std::string along = key + ".cuts." + std::string(1, "xyz"[d]);
    if (int(cuts.size()) != p - 1)
      throw InputError(along, std::to_string(cuts.size()) + " planes", std::to_string(p - 1) + " interior planes (process_grid)");
    for (std::size_t c = 0; c < cuts.size(); ++c)
      if (!(cuts[c] > lo && cuts[c] < hi) || (c > 0 && !(cuts[c] > cuts[c - 1])))
        throw InputError(along, std::to_string(cuts[c]), "increasing planes inside the box");
    blocks[d] = cells_per_slab(cuts, n, lo, h);
    for (int c : blocks[d])
      if (c < 1) throw InputError(along, "", "planes that leave every block at least one cell");
  }
  return blocks;
}

}  // namespace

CellMultigrid::CellMultigrid(const FluidGrid& grid, int pre, int post, int coarse, bool coarse_direct, int ghost_layers,
                             const LevelsAsOn& as_on, bool level_pairs)
    : grid_(grid), pre_(pre), post_(post), coarse_(coarse), ghost_layers_(ghost_layers), coarse_direct_(coarse_direct) {
  DM fine = grid.pressure_dm();
  PetscInt M, N, P, pm, pn, pp;
  check(DMDAGetInfo(fine, nullptr, &M, &N, &P, &pm, &pn, &pp, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr),
        "DMDAGetInfo");
  const PetscInt* own0[3];
  check(DMDAGetOwnershipRanges(fine, &own0[0], &own0[1], &own0[2]), "DMDAGetOwnershipRanges");
  MPI_Comm_dup(grid.comm(), &transfer_comm_);
  std::array<int, 3> procs{int(pm), int(pn), int(pp)};
  std::array<std::vector<int>, 3> blocks;
  for (int d = 0; d < 3; ++d) blocks[d].assign(own0[d], own0[d] + procs[d]);
  const std::array<bool, 3> periodic{grid.periodic(0), grid.periodic(1), grid.periodic(2)};
  if (as_on.any()) {
    plan_ = plan_multigrid(blocks_as_on(grid, as_on), periodic, ghost_layers_, level_pairs);
    for (MultigridLevelPlan& L : plan_) {  // held whole by this one process
      for (int d = 0; d < 3; ++d) L.blocks[d] = {L.n[d]}, L.parts[d].clear();
      L.merged = {};
      L.crosses = {};
      L.halo = periodic[0] || periodic[1] || periodic[2];
      L.layers = 1;  // the same numbers with either (the passes' ghosts on periodic sides only)
    }
  } else {
    plan_ = plan_multigrid(blocks, periodic, ghost_layers_, level_pairs);
  }
  const auto& plan = plan_;
  // The ranks of the level being made, known on every rank: the rank (on transfer_comm_) of each
  // block (x fastest), and this rank's place.
  std::vector<int> rank_of(std::size_t{1} * procs[0] * procs[1] * procs[2]);
  for (std::size_t r = 0; r < rank_of.size(); ++r) rank_of[r] = int(r);
  auto linear = [](const std::array<int, 3>& c, const std::array<int, 3>& p) { return c[0] + p[0] * (c[1] + p[1] * c[2]); };
  const int me = grid.rank();
  std::array<int, 3> coords{me % procs[0], (me / procs[0]) % procs[1], me / (procs[0] * procs[1])};
  bool active = true;
  MPI_Comm comm = grid.comm();
  for (const MultigridLevelPlan& plan_level : plan) {
    auto L = std::make_unique<Level>();
    Level::Part part;
    std::vector<Level::Part> parts;
    if (plan_level.gathered()) {
      // Each finer rank's part: the aggregates of its block; ranks 2c and 2c + 1 along a merged
      // direction hand theirs to 2c, which owns both from here down.
      const auto& merge = plan_level.merged;
      auto part_of = [&](const std::array<int, 3>& c) {
        Level::Part q;
        q.rank = rank_of[std::size_t(linear(c, procs))];
        for (int d = 0; d < 3; ++d) {
          for (int b = 0; b < c[d]; ++b) q.s[d] += plan_level.parts[d][std::size_t(b)];
          q.m[d] = plan_level.parts[d][std::size_t(c[d])];
        }
        return q;
      };
      const std::array<int, 3> next_procs = plan_level.procs();
      std::vector<int> next_rank_of(std::size_t{1} * next_procs[0] * next_procs[1] * next_procs[2]);
      for (int c2 = 0; c2 < next_procs[2]; ++c2)
        for (int c1 = 0; c1 < next_procs[1]; ++c1)
          for (int c0 = 0; c0 < next_procs[0]; ++c0) {
            const std::array<int, 3> c{c0, c1, c2}, f{merge[0] ? 2 * c0 : c0, merge[1] ? 2 * c1 : c1, merge[2] ? 2 * c2 : c2};
            next_rank_of[std::size_t(linear(c, next_procs))] = rank_of[std::size_t(linear(f, procs))];
          }
      std::array<int, 3> next_coords = coords;
      bool owner = active;
      for (int d = 0; d < 3; ++d)
        if (merge[d]) next_coords[d] = coords[d] / 2, owner = owner && coords[d] % 2 == 0;
      if (active) {
        part = part_of(coords);
        part.rank = next_rank_of[std::size_t(linear(next_coords, next_procs))];  // its owner
      }
      if (owner)  // the finer blocks whose aggregates this rank owns, in their ranks' order
        for (int c2 = 0; c2 < procs[2]; ++c2)
          for (int c1 = 0; c1 < procs[1]; ++c1)
            for (int c0 = 0; c0 < procs[0]; ++c0) {
              const std::array<int, 3> c{c0, c1, c2};
              bool mine = true;
              for (int d = 0; d < 3; ++d) mine = mine && (merge[d] ? c[d] / 2 : c[d]) == next_coords[d];
              if (mine) parts.push_back(part_of(c));
            }
      MPI_Comm next = MPI_COMM_NULL;
      MPI_Comm_split(grid.comm(), owner ? 0 : MPI_UNDEFINED, linear(next_coords, next_procs), &next);
      if (next != MPI_COMM_NULL) level_comms_.push_back(next);
      comm = next;
      active = owner;
      procs = next_procs;
      coords = next_coords;
      rank_of = next_rank_of;
    }
    L->n = plan_level.n;
    L->fine_start = plan_level.fine_start;
    for (int d = 0; d < 3 && !L->fine_start[d].empty(); ++d)
      for (int I = 0; I < L->n[d]; ++I) L->aggregate_of[d].insert(L->aggregate_of[d].end(), L->width(d, I), I);
    L->active = active;
    L->comm = active ? comm : MPI_COMM_NULL;
    L->procs = procs;
    L->coords = coords;
    L->gathered = plan_level.gathered();
    L->crosses = plan_level.crossing();
    L->part = part;
    L->parts = parts;
    L->inbox.resize(parts.size());
    if (active) {
      L->layers = plan_level.layers;
      const int w = L->layers;
      for (int d = 0; d < 3; ++d) {
        const auto& own = plan_level.blocks[d];
        L->s[d] = 0;
        for (int c = 0; c < coords[d]; ++c) L->s[d] += own[std::size_t(c)];
        L->m[d] = own[std::size_t(coords[d])];
        L->gs[d] = L->s[d] - w;  // ghosts on every side, beyond a domain face too (left at 0 there)
        L->gm[d] = L->m[d] + 2 * w;
      }
      L->stride = {1, L->gm[0], std::ptrdiff_t(L->gm[0]) * L->gm[1]};
      CellHalo::Block block;
      block.procs = procs;
      block.coords = coords;
      for (int d = 0; d < 3; ++d) block.periodic[d] = grid.periodic(d);
      block.s = L->s;
      block.m = L->m;
      block.gs = L->gs;
      block.gm = L->gm;
      L->block = block;
      L->halo = std::make_unique<CellHalo>(comm, block, w, w == 1 ? CellHalo::Stencil::star : CellHalo::Stencil::box);
      if (w == 2) {
        for (int d = 0; d < 3; ++d)
          if (!L->halo->fills(d, 1)) block.m[d] += 1;  // the high domain face's coefficients
        L->face_halo = std::make_unique<CellHalo>(comm, block, w, CellHalo::Stencil::box);
      }
      const std::size_t size = std::size_t(L->gm[0]) * L->gm[1] * L->gm[2];
      for (auto& c : L->coef) c.assign(size, 0.0f);
      if (levels_.empty())
        for (auto& c : L->op_coef) c.assign(size, 0.0);
      L->inv_diag.assign(size, 0.0f);
      L->x.assign(size, 0.0);  // the ghosts beyond a domain face stay 0 (an outflow face's p = 0)
      L->b.assign(size, 0.0);
    }
    levels_.push_back(std::move(L));
  }
  // Aggregates across a cut: the one-layer exchanges of the finer level's residuals and
  // coefficients and of the coarser level's corrections and coefficients (on levels not gathered,
  // so on the same ranks and communicator).
  for (std::size_t l = 1; l < levels_.size(); ++l) {
    if (!levels_[l]->crosses || !levels_[l]->active) continue;
    for (Level* L : {levels_[l - 1].get(), levels_[l].get()}) {
      if (L->cross_halo) continue;
      L->cross_halo = std::make_unique<CellHalo>(L->comm, L->block, 1, CellHalo::Stencil::box);
      CellHalo::Block faces = L->block;
      for (int d = 0; d < 3; ++d)
        if (!L->cross_halo->fills(d, 1)) faces.m[d] += 1;  // the high domain face's coefficients
      L->cross_coef_halo = std::make_unique<CellHalo>(L->comm, faces, 1, CellHalo::Stencil::box);
    }
    levels_[l - 1]->r.assign(levels_[l - 1]->x.size(), 0.0);
  }
}

CellMultigrid::~CellMultigrid() {
  if (coarse_ksp_) KSPDestroy(&coarse_ksp_);
  if (coarse_A_) MatDestroy(&coarse_A_);
  if (coarse_b_) VecDestroy(&coarse_b_);
  if (coarse_x_) VecDestroy(&coarse_x_);
  for (MPI_Comm& c : level_comms_) MPI_Comm_free(&c);
  if (transfer_comm_ != MPI_COMM_NULL) MPI_Comm_free(&transfer_comm_);
}

void CellMultigrid::exchange(Level& L, std::initializer_list<std::vector<double>*> fields) { exchange_on(L.halo, fields); }

void CellMultigrid::exchange_on(const std::unique_ptr<CellHalo>& halo, std::initializer_list<std::vector<double>*> fields) {
  if (!halo || !halo->active()) return;  // one rank, nothing periodic: no ghost has a source
  const double start = MPI_Wtime();
  ++exchanges_;
  halo->exchange(fields);
  exchange_seconds_ += MPI_Wtime() - start;
}

void CellMultigrid::set_inverse_diagonal(Level& L) {
  // With two layers the ghost cells' face coefficients come from their owners first, and the first
  // ghost layer's inverse diagonal is computed as its owner computes it.
  std::array<int, 3> s = L.s, m = L.m;
  if (L.face_halo && L.face_halo->active()) {
    const double start = MPI_Wtime();
    L.face_halo->exchange({&L.coef[0], &L.coef[1], &L.coef[2]});
    exchange_seconds_ += MPI_Wtime() - start;
    for (int d = 0; d < 3; ++d) {
      s[d] = L.s[d] - (L.halo->fills(d, 0) ? 1 : 0);
      m[d] = L.m[d] + (L.s[d] - s[d]) + (L.halo->fills(d, 1) ? 1 : 0);
    }
  }
  for_owned(s, m, [&](int i, int j, int k) {
    const std::size_t c = L.at(i, j, k);
    const double sum = coefficient_sum(L, c);
    L.inv_diag[c] = float(sum > 0 ? 1 / sum : 1.0);
  });
}

void CellMultigrid::set_coefficients(const std::vector<double>& rho, bool coarse) {
  const FluidGrid& g = grid_;
  Level& F = *levels_[0];
  const double h[3] = {g.h(0), g.h(1), g.h(2)};
  const double area_over_h[3] = {h[1] * h[2] / h[0], h[0] * h[2] / h[1], h[0] * h[1] / h[2]};
  // Finest level: the coefficients of pressure_poisson.cpp, for the low faces of owned cells and
  // the high face of the last owned cell along each direction. An outflow face couples to a
  // ghost held at 0 (p = 0 on the face, half a cell away): twice the coefficient.
  for (int d = 0; d < 3; ++d) {
    std::array<int, 3> m = F.m;
    m[d] += 1;
    const int n = g.cells()[d];
    for_owned(F.s, m, [&](int i, int j, int k) {
      const int idx[3] = {i, j, k};
      const std::size_t c = g.at(i, j, k), fc = F.at(i, j, k);
      double coef;
      if (!g.periodic(d) && (idx[d] == 0 || idx[d] == n)) {
        const bool low = idx[d] == 0;
        coef = g.boundary(d, low ? 0 : 1) == BoundaryKind::outflow ? 2 * area_over_h[d] / rho[low ? c : c - g.stride(d)]
                                                                   : 0.0;
      } else {
        coef = area_over_h[d] / (0.5 * (rho[c] + rho[c - g.stride(d)]));
      }
      F.op_coef[d][fc] = coef;
      F.coef[d][fc] = float(coef);
    });
  }
  // Coarse levels, each computed on the next finer level's ranks (a gathered level's parts sent
  // to their owners: per part, the faces along x, then y, then z, each over the part's cells and
  // its high face).
  for (std::size_t l = 1; coarse && l < levels_.size(); ++l) {
    Level& f = *levels_[l - 1];
    Level& C = *levels_[l];
    if (!f.active) break;  // nor on any coarser level
    // The coarse face on the low side of cell (I, J, K) along d.
    auto face = [&](int d, int I, int J, int K) {
      const int idx[3] = {I, J, K};
      int lo[3], hi[3];  // the fine faces on the coarse face's plane
      for (int e = 0; e < 3; ++e) {
        lo[e] = C.fine_start[e][idx[e]];
        hi[e] = e == d ? lo[e] + 1 : C.fine_start[e][idx[e] + 1];
      }
      double sum = 0;
      for (int c = lo[2]; c < hi[2]; ++c)
        for (int b = lo[1]; b < hi[1]; ++b)
          for (int a = lo[0]; a < hi[0]; ++a) sum += f.coef[d][f.at(a, b, c)];
      // Over the ratio of the coarse centres' distance to the fine ones' (theory F9a).
      return sum / coarse_face_distance(plan_[l - 1], plan_[l], d, idx[d], grid_.periodic(d));
    };
    auto with_high_face = [](std::array<int, 3> m, int d) {
      m[d] += 1;
      return m;
    };
    if (!C.gathered) {
      // Across a cut the finer level's next cells' coefficients come first; a coarse high face
      // whose fine face lies past them is the neighbour's low one, which it computes and sends.
      // (Once a set-up, as set_inverse_diagonal's: timed, not counted among a cycle's exchanges.)
      auto coefficients = [&](Level& L) {
        if (!L.cross_coef_halo->active()) return;
        const double start = MPI_Wtime();
        L.cross_coef_halo->exchange({&L.coef[0], &L.coef[1], &L.coef[2]});
        exchange_seconds_ += MPI_Wtime() - start;
      };
      if (C.crosses) coefficients(f);
      for (int d = 0; d < 3; ++d)
        for_owned(C.s, with_high_face(C.m, d), [&](int I, int J, int K) {
          const int idx[3] = {I, J, K};
          if (idx[d] == C.s[d] + C.m[d] && C.fine_start[d][idx[d]] > f.s[d] + f.m[d]) return;
          C.coef[d][C.at(I, J, K)] = float(face(d, I, J, K));
        });
      if (C.crosses) coefficients(C);
      continue;
    }
    C.staging.clear();
    for (int d = 0; d < 3; ++d)
      for_owned(C.part.s, with_high_face(C.part.m, d), [&](int I, int J, int K) { C.staging.push_back(face(d, I, J, K)); });
    auto size = [&](const Level::Part& q) {
      std::size_t n = 0;
      for (int d = 0; d < 3; ++d) {
        const auto m = with_high_face(q.m, d);
        n += std::size_t(m[0]) * m[1] * m[2];
      }
      return n;
    };
    gather(C, C.staging, size, [&](const Level::Part& q, const double* v) {
      for (int d = 0; d < 3; ++d)
        for_owned(q.s, with_high_face(q.m, d), [&](int I, int J, int K) { C.coef[d][C.at(I, J, K)] = float(*v++); });
    });
  }
  for (std::size_t l = 0; l < (coarse ? levels_.size() : 1); ++l) {
    Level& L = *levels_[l];
    if (!L.active) break;
    set_inverse_diagonal(L);
  }
  if (coarse && coarse_direct_ && levels_.back()->active) assemble_coarsest();
}

long CellMultigrid::coarsest_cells() const {
  const auto& n = levels_.back()->n;
  return long(n[0]) * n[1] * n[2];
}

int CellMultigrid::two_layer_levels() const {
  return int(std::count_if(levels_.begin(), levels_.end(), [](const auto& L) { return L->active && L->layers == 2; }));
}

int CellMultigrid::gathered_levels() const {
  return int(std::count_if(levels_.begin(), levels_.end(), [](const auto& L) { return L->gathered; }));
}

void CellMultigrid::smooth(Level& L, int sweeps, bool reverse, bool from_zero, bool ghosts_after) {
  const float* const cf[3] = {L.coef[0].data(), L.coef[1].data(), L.coef[2].data()};
  const float* const inv = L.inv_diag.data();
  const double* const b = L.b.data();
  double* const x = L.x.data();
  const std::ptrdiff_t sy = L.stride[1], sz = L.stride[2];
  const std::array<int, 3> s = L.s, e{L.s[0] + L.m[0], L.s[1] + L.m[1], L.s[2] + L.m[2]};
  // The cells of `colour` in [i_begin, i_end) of row (j, k): x = (b + sum of c_f x_nb) / diag.
  auto update = [&](int i_begin, int i_end, int j, int k, int colour) {
    if (((i_begin + j + k) & 1) != colour) ++i_begin;
    if (i_begin >= i_end) return;
    const std::size_t end = L.at(i_end - 1, j, k) + 1;
    for (std::size_t c = L.at(i_begin, j, k); c < end; c += 2) {
      const double sum = b[c] + double(cf[0][c]) * x[c - 1] + double(cf[0][c + 1]) * x[c + 1] +
                         double(cf[1][c]) * x[c - sy] + double(cf[1][c + sy]) * x[c + sy] +
                         double(cf[2][c]) * x[c - sz] + double(cf[2][c + sz]) * x[c + sz];
      x[c] = sum * double(inv[c]);
    }
  };
  // From x = 0, the first colour's cells of a row take b / diag and the others 0: every owned
  // cell is written, so x needs no clearing (its ghosts beyond the domain stay 0).
  auto first_pass = [&](int j, int k, int colour) {
    const std::size_t row = L.at(s[0], j, k);
    const int parity = (s[0] + j + k) & 1;
    for (int i = 0; i < L.m[0]; ++i)
      x[row + i] = ((parity + i) & 1) == colour ? b[row + i] * double(inv[row + i]) : 0.0;
  };
  // A pass reads the other colour's values of the pass before. Over the cells at depth >= p from
  // every side whose ghosts an exchange fills (a neighbour rank or a periodic image), pass p reads
  // only cells that pass p - 1 has reached in the same stream, if it trails pass p - 1 by a plane:
  // all the sweeps' passes go down the level in one stream, each a plane behind the one before.
  // The shells left (depth < p) take pass p in pass order, after an exchange where the ghosts they
  // read are not yet current. With one ghost layer that is every pass. With two, an exchange
  // brings the neighbours' two outer layers, whose cells of the pass's colour then hold the pass
  // before's values; the pass updates the first ghost layer too (its cells read only the
  // exchanged layers and their own), and the next pass needs no exchange: one exchange a sweep.
  // Every cell reads the same values as in separate passes with an exchange after each: the same
  // numbers, and the level streamed once instead of once a pass.
  const int passes = 2 * sweeps;
  const int w = L.layers;
  std::array<int, 3> fill_lo{}, fill_hi{};
  for (int d = 0; d < 3; ++d) {
    fill_lo[d] = L.halo->fills(d, 0) ? 1 : 0;
    fill_hi[d] = L.halo->fills(d, 1) ? 1 : 0;
  }
  // The cells at depth >= p: [lo, hi).
  auto deep = [&](int p, std::array<int, 3>& lo, std::array<int, 3>& hi) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(s[d] + p * fill_lo[d], e[d]);
      hi[d] = std::max(lo[d], e[d] - p * fill_hi[d]);
    }
  };
  // The first ghost layer, on the sides an exchange fills (edges and corners included).
  auto ghost_layer = [&](int colour) {
    for (int k = s[2] - fill_lo[2]; k < e[2] + fill_hi[2]; ++k)
      for (int j = s[1] - fill_lo[1]; j < e[1] + fill_hi[1]; ++j) {
        if (k < s[2] || k >= e[2] || j < s[1] || j >= e[1]) {
          update(s[0] - fill_lo[0], e[0] + fill_hi[0], j, k, colour);
        } else {
          if (fill_lo[0]) update(s[0] - 1, s[0], j, k, colour);
          if (fill_hi[0]) update(e[0], e[0] + 1, j, k, colour);
        }
      }
  };
  auto colour_of = [&](int p) { return (p & 1) == (reverse ? 1 : 0) ? 0 : 1; };
  // The passes that follow an exchange: from zero, pass 1 (pass 0 reads no neighbour), 1 + w, ...;
  // else pass 0 (after the correction), w, 2 w, ...
  const int first = from_zero ? 1 : 0;
  auto after_exchange = [&](int p) { return p >= first && (p - first) % w == 0; };
  // From zero, the first exchange also brings the right-hand side's ghosts (the ghost layer's
  // updates read them; they stay current until the level's next right-hand side).
  auto exchange_before = [&](int p) {
    if (from_zero && p == first && w == 2)
      exchange(L, {&L.x, &L.b});
    else
      exchange(L, {&L.x});
  };
  if (!from_zero && passes > 0) exchange_before(0);
  std::array<int, 3> lo{}, hi{};
  for (int k = s[2]; k < e[2] + passes - 1; ++k)
    for (int p = 0; p < passes; ++p) {
      const int kp = k - p;
      deep(p, lo, hi);
      if (kp < lo[2] || kp >= hi[2]) continue;
      if (p == 0 && from_zero) {
        for (int j = s[1]; j < e[1]; ++j) first_pass(j, kp, colour_of(0));
        continue;
      }
      for (int j = lo[1]; j < hi[1]; ++j) update(lo[0], hi[0], j, kp, colour_of(p));
    }
  // Pass 0 without an exchange since: its ghost layer reads the prolonged values beside it, which
  // only pass 1's shell changes.
  if (!from_zero && passes > 0 && w == 2) ghost_layer(colour_of(0));
  for (int p = 1; p < passes; ++p) {
    if (after_exchange(p)) {
      exchange_before(p);
      if (w == 2) ghost_layer(colour_of(p));
    }
    deep(p, lo, hi);
    for (int k = s[2]; k < e[2]; ++k)
      for (int j = s[1]; j < e[1]; ++j) {
        if (k < lo[2] || k >= hi[2] || j < lo[1] || j >= hi[1]) {
          update(s[0], e[0], j, k, colour_of(p));
        } else {
          update(s[0], lo[0], j, k, colour_of(p));
          update(hi[0], e[0], j, k, colour_of(p));
        }
      }
  }
  // The first ghost layer holds both colours' last values where the last pass followed an
  // exchange (two layers); else one more exchange.
  if (ghosts_after && passes > 0 && !(w == 2 && after_exchange(passes - 1))) exchange(L, {&L.x});
}

template <class Size, class Unpack>
void CellMultigrid::gather(Level& C, const std::vector<double>& mine, Size&& size, Unpack&& unpack) {
  const double start = MPI_Wtime();
  const int tag = 700;
  if (!C.active) {  // the part goes to its owner
    MPI_Send(mine.data(), int(mine.size()), MPI_DOUBLE, C.part.rank, tag, transfer_comm_);
    transfer_traffic_.messages += 1, transfer_traffic_.bytes += 8.0 * double(mine.size());
  } else {
    const int me = grid_.rank();  // transfer_comm_ duplicates the grid's communicator
    C.requests.clear();
    for (std::size_t p = 0; p < C.parts.size(); ++p) {
      if (C.parts[p].rank == me) continue;
      C.inbox[p].resize(size(C.parts[p]));
      C.requests.emplace_back();
      MPI_Irecv(C.inbox[p].data(), int(C.inbox[p].size()), MPI_DOUBLE, C.parts[p].rank, tag, transfer_comm_,
                &C.requests.back());
    }
    MPI_Waitall(int(C.requests.size()), C.requests.data(), MPI_STATUSES_IGNORE);
    for (std::size_t p = 0; p < C.parts.size(); ++p) unpack(C.parts[p], C.parts[p].rank == me ? mine.data() : C.inbox[p].data());
  }
  exchange_seconds_ += MPI_Wtime() - start;
}

template <class Pack>
void CellMultigrid::scatter(Level& C, std::vector<double>& mine, Pack&& pack) {
  const double start = MPI_Wtime();
  const int tag = 701;
  const std::size_t count = std::size_t(C.part.m[0]) * C.part.m[1] * C.part.m[2];
  mine.resize(count);
  if (!C.active) {
    MPI_Recv(mine.data(), int(count), MPI_DOUBLE, C.part.rank, tag, transfer_comm_, MPI_STATUS_IGNORE);
  } else {
    C.requests.clear();
    for (std::size_t p = 0; p < C.parts.size(); ++p) {
      const bool own = C.parts[p].rank == grid_.rank();  // transfer_comm_ duplicates the grid's
      std::vector<double>& out = own ? mine : C.inbox[p];
      out.clear();
      pack(C.parts[p], out);
      if (own) continue;
      C.requests.emplace_back();
      MPI_Isend(out.data(), int(out.size()), MPI_DOUBLE, C.parts[p].rank, tag, transfer_comm_, &C.requests.back());
      transfer_traffic_.messages += 1, transfer_traffic_.bytes += 8.0 * double(out.size());
    }
    MPI_Waitall(int(C.requests.size()), C.requests.data(), MPI_STATUSES_IGNORE);
  }
  exchange_seconds_ += MPI_Wtime() - start;
}

void CellMultigrid::restrict_residual(Level& L, Level& C) {
  // The residual's rows are cell integrals: a coarse cell's right-hand side is the sum of its fine
  // cells' residuals, taken in the fine level's storage order (a coarse cell's fine cells k, then
  // j, then i ascending); the aggregates lie within each rank's block. The pre-smoothing ends with
  // a pass over colour 1, which solves those rows given their neighbours, unchanged since: their
  // residual is zero (to the rounding of x = s / diag), and only colour 0's are summed. Into the
  // coarse level's owned cells, or, gathered, into this rank's part sent to its owner.
  double* out;
  Box box;
  if (C.gathered) {
    box = {C.part.s, C.part.m};
    C.staging.assign(box.size(), 0.0);
    out = C.staging.data();
  } else {
    box = {C.gs, C.gm};
    for_owned(C.s, C.m, [&](int I, int J, int K) { C.b[C.at(I, J, K)] = 0; });
    out = C.b.data();
  }
  if (C.crosses) {
    // The aggregates across a cut reach the next rank's first cells: every rank's residuals of
    // its owned cells (the others 0), exchanged, then summed over this rank's aggregates, each
    // coarse cell's fine cells in the same order as within a block (k, then j, then i).
    for (int k = L.s[2]; k < L.s[2] + L.m[2]; ++k)
      for (int j = L.s[1]; j < L.s[1] + L.m[1]; ++j) {
        const std::size_t c0 = L.at(L.s[0], j, k);
        for (int i = (L.s[0] + j + k) & 1; i < L.m[0]; i += 2) L.r[c0 + i] = residual(L, c0 + i);
      }
    exchange_on(L.cross_halo, {&L.r});
    std::array<int, 3> lo{}, hi{};
    for (int d = 0; d < 3; ++d) lo[d] = C.fine_start[d][C.s[d]], hi[d] = C.fine_start[d][C.s[d] + C.m[d]];
    const int* const agg = C.aggregate_of[0].data();
    for (int k = lo[2]; k < hi[2]; ++k)
      for (int j = lo[1]; j < hi[1]; ++j) {
        double* const coarse_row = out + box.at(box.s[0], C.aggregate_of[1][j], C.aggregate_of[2][k]) - box.s[0];
        const double* const r = L.r.data() + L.at(lo[0], j, k) - lo[0];
        for (int i = lo[0] + ((lo[0] + j + k) & 1); i < hi[0]; i += 2) coarse_row[agg[i]] += r[i];
      }
    return;
  }
  const int* const agg = C.aggregate_of[0].data() + L.s[0];
  for (int k = L.s[2]; k < L.s[2] + L.m[2]; ++k)
    for (int j = L.s[1]; j < L.s[1] + L.m[1]; ++j) {
      double* const coarse_row = out + box.at(box.s[0], C.aggregate_of[1][j], C.aggregate_of[2][k]) - box.s[0];
      const std::size_t c0 = L.at(L.s[0], j, k);
      for (int i = (L.s[0] + j + k) & 1; i < L.m[0]; i += 2) coarse_row[agg[i]] += residual(L, c0 + i);
    }
  if (C.gathered)
    gather(C, C.staging, [](const Level::Part& q) { return Box{q.s, q.m}.size(); },
           [&](const Level::Part& q, const double* v) {
             for_owned(q.s, q.m, [&](int I, int J, int K) { C.b[C.at(I, J, K)] = *v++; });
           });
}

void CellMultigrid::prolong(Level& C, Level& L) {
  // Injection (the restriction's transpose): each fine cell gains its aggregate's correction,
  // from the coarse level's owned cells or, gathered, from this rank's part sent by its owner.
  const double* in;
  Box box;
  if (C.gathered) {
    scatter(C, C.staging, [&](const Level::Part& q, std::vector<double>& out) {
      for_owned(q.s, q.m, [&](int I, int J, int K) { out.push_back(C.x[C.at(I, J, K)]); });
    });
    box = {C.part.s, C.part.m};
    in = C.staging.data();
  } else {
    // Across a cut, the first cells take the correction of the neighbour's aggregate.
    if (C.crosses) exchange_on(C.cross_halo, {&C.x});
    box = {C.gs, C.gm};
    in = C.x.data();
  }
  const int* const agg = C.aggregate_of[0].data() + L.s[0];
  for (int k = L.s[2]; k < L.s[2] + L.m[2]; ++k)
    for (int j = L.s[1]; j < L.s[1] + L.m[1]; ++j) {
      const double* const coarse_row = in + box.at(box.s[0], C.aggregate_of[1][j], C.aggregate_of[2][k]) - box.s[0];
      double* const x = L.x.data() + L.at(L.s[0], j, k);
      for (int i = 0; i < L.m[0]; ++i) x[i] += coarse_row[agg[i]];
    }
}

void CellMultigrid::cycle(std::size_t l) {
  Level& L = *levels_[l];
  if (l + 1 == levels_.size()) {
    if (coarse_direct_) {  // the prolongation reads only owned cells
      solve_coarsest();
      return;
    }
    smooth(L, coarse_ / 2, false, true, false);
    smooth(L, coarse_ / 2, true, false, false);
    return;
  }
  smooth(L, pre_, false, true, true);  // the restriction reads the first ghost layer
  Level& C = *levels_[l + 1];
  restrict_residual(L, C);
  if (C.active) cycle(l + 1);  // else its owner's correction comes back in the prolongation
  prolong(C, L);
  // The coarser level reads only owned cells of this one, and apply() copies only owned cells out.
  smooth(L, post_, true, false, false);
}

void CellMultigrid::apply_operator(Vec xin, Vec yout) {
  Level& F = *levels_[0];
  const int nx = F.m[0];
  const PetscScalar* in;
  check(VecGetArrayRead(xin, &in), "VecGetArrayRead");
  for_rows(F, [&](std::size_t row, std::size_t n) { std::copy(in + n, in + n + nx, F.x.data() + row); });
  check(VecRestoreArrayRead(xin, &in), "VecRestoreArrayRead");
  exchange(F, {&F.x});
  PetscScalar* out;
  check(VecGetArray(yout, &out), "VecGetArray");
  const double* const cx = F.op_coef[0].data();
  const double* const cy = F.op_coef[1].data();
  const double* const cz = F.op_coef[2].data();
  const double* const x = F.x.data();
  const std::ptrdiff_t sy = F.stride[1], sz = F.stride[2];
  for_rows(F, [&](std::size_t row, std::size_t n) {
    double* const o = out + n;
    for (int i = 0; i < nx; ++i) {
      const std::size_t c = row + i;
      const double diag = (cx[c] + cx[c + 1]) + (cy[c] + cy[c + sy]) + (cz[c] + cz[c + sz]);
      o[i] = diag * x[c] - (cx[c] * x[c - 1] + cx[c + 1] * x[c + 1]) - (cy[c] * x[c - sy] + cy[c + sy] * x[c + sy]) -
             (cz[c] * x[c - sz] + cz[c + sz] * x[c + sz]);
    }
  });
  check(VecRestoreArray(yout, &out), "VecRestoreArray");
}

void CellMultigrid::apply(Vec xin, Vec yout) {
  Level& F = *levels_[0];
  const int nx = F.m[0];
  const PetscScalar* in;
  check(VecGetArrayRead(xin, &in), "VecGetArrayRead");
  for_rows(F, [&](std::size_t row, std::size_t n) { std::copy(in + n, in + n + nx, F.b.data() + row); });
  check(VecRestoreArrayRead(xin, &in), "VecRestoreArrayRead");
  ++cycles_;
  cycle(0);
  PetscScalar* out;
  check(VecGetArray(yout, &out), "VecGetArray");
  for_rows(F, [&](std::size_t row, std::size_t n) { std::copy(F.x.data() + row, F.x.data() + row + nx, out + n); });
  check(VecRestoreArray(yout, &out), "VecRestoreArray");
}

CellHalo::Traffic CellMultigrid::halo_traffic() const {
  CellHalo::Traffic t = transfer_traffic_;
  for (const auto& L : levels_)
    if (L->halo) t += L->halo->traffic();
  return t;
}

}  // namespace tessera
