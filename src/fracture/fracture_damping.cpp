// SPDX-License-Identifier: MIT
// The bond dashpots of every intact bond together, by the theta method (docs/theory.md B9a).
//
// Over a step h the dashpots alone change the elements' velocities V = (v, w) by
//   M dV/dt = -C V,   theta method:   (M + theta h C) dV = -h C V,   V+ = V + dV,
// with M each element's mass and world inertia and C the sum over the bonds' vertex units of
// J^T D J: J maps the two elements' velocities to the vertex's relative velocity
// du = (v_j + w_j x r_j) - (v_i + w_i x r_i), D = (A/3) (c_n n n^T + c_s (1 - n n^T)) in the
// master face's frame (B2). The system is solved by conjugate gradients preconditioned by each
// element's 6 x 6 block (as a change of variables, below); the impulses h D (theta du+ +
// (1 - theta) du) are then made unit by unit, equal and opposite at the vertex, so momentum is kept
// to round-off whatever the solve's residual.
// Elements' positions are those of the call (the dashpots' frame does not turn in h).
#include <algorithm>
#include <cmath>
#include <optional>

#include "core/errors.hpp"
#include "core/exact_sum.hpp"
#include "fracture/fracture_solver.hpp"

namespace tessera {

namespace {

using Block6 = std::array<double, 36>;  // a 6 x 6 block, row-major

// The inverse of the Cholesky factor L (D = L L^T) of a symmetric positive definite 6 x 6 block,
// lower triangular, row-major (zeros above the diagonal). Six divisions and six square roots.
Block6 cholesky_inverse(const Block6& a) {
  double l[6][6] = {}, d[6];  // d: 1 / L_ii
  for (int j = 0; j < 6; ++j) {
    double s = a[6 * j + j];
    for (int k = 0; k < j; ++k) s -= l[j][k] * l[j][k];
    l[j][j] = std::sqrt(s);
    d[j] = 1.0 / l[j][j];
    for (int i = j + 1; i < 6; ++i) {
      double t = a[6 * i + j];
      for (int k = 0; k < j; ++k) t -= l[i][k] * l[j][k];
      l[i][j] = t * d[j];
    }
  }
  Block6 m{};  // L^-1
  for (int j = 0; j < 6; ++j) {
    m[6 * j + j] = d[j];
    for (int i = j + 1; i < 6; ++i) {
      double t = 0;
      for (int k = j; k < i; ++k) t -= l[i][k] * m[6 * k + j];
      m[6 * i + j] = t * d[i];
    }
  }
  return m;
}

}  // namespace

void FractureSolver::damp_bonds(double h) {
  if (!settings_.damping || !settings_.implicit_damping) return;
  new_epoch();
  damping_links(h);
  damping_matrix(h);
  damping_solve();
  new_epoch();
}

void FractureSolver::damping_links(double h) {
  // The vertex units of the intact bonds with an element here, in bond order, in world frame (the
  // master face's normal, each element's lever), with h folded in; and what travels per iteration:
  // to each rank, my elements bonded to its elements, and from it, the same of its elements. A bond
  // that broke since the last call leaves its slot, and its elements' diagonal blocks are remade.
  const int rank = decomp_.rank();
  const BondLaw& law = settings_.bond;
  DampingWork& w = damping_;
  const std::size_t n = block_.size();
  w.units.clear(), w.links.clear();
  w.remade.assign(n, 0);
  if (w.slot.size() != block_.bonds.size()) w.slot.assign(block_.bonds.size(), -1), w.h = 0;
  std::vector<std::array<int, 2>>&sent = w.sent, &read = w.read;
  sent.clear(), read.clear();
  for (std::size_t b = 0; b < block_.bonds.size(); ++b) {
    const BondGeometry& g = block_.bonds[b];
    int& slot = w.slot[b];
    if (broken_[b]) {
      if (slot >= 0 && w.live[static_cast<std::size_t>(slot)])
        w.live[static_cast<std::size_t>(slot)] = 0, w.remade[static_cast<std::size_t>(g.master)] = 1,
                                            w.remade[static_cast<std::size_t>(g.slave)] = 1;
      continue;
    }
    const int oi = owner_[static_cast<std::size_t>(g.master)], oj = owner_[static_cast<std::size_t>(g.slave)];
    if (oi != rank && oj != rank) continue;
    if (oi != oj) {
      const bool mine_i = oi == rank;
      sent.push_back({mine_i ? oj : oi, mine_i ? g.master : g.slave});
      read.push_back({mine_i ? oj : oi, mine_i ? g.slave : g.master});
    }
    if (slot < 0) {  // a bond first seen here: every block is made again (the first call)
      slot = static_cast<int>(w.live.size());
      w.live.push_back(0), w.to_i.emplace_back(), w.to_j.emplace_back(), w.off.emplace_back(), w.off_f.emplace_back();
      w.h = 0;
    }
    const Pose& pi = pose(static_cast<std::size_t>(g.master));
    const Pose& pj = pose(static_cast<std::size_t>(g.slave));
    const Vec3 nw = pi.rot(g.normal);
    const double share = settings_.damping_theta * h * g.area / 3;
    w.links.push_back({static_cast<int>(b), g.master, g.slave, slot, oi == rank, oj == rank});
    for (int k = 0; k < 3; ++k)
      w.units.push_back({nw, pi.rot(g.at_master[k]), pj.rot(g.at_slave[k]), share * law.cn, share * law.cs});
  }
  for (auto* v : {&sent, &read}) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  }
  w.neighbours.clear(), w.send_elements.clear();
  for (const auto& [r, e] : sent) {
    if (w.neighbours.empty() || w.neighbours.back() != r) w.neighbours.push_back(r), w.send_elements.emplace_back();
    w.send_elements.back().push_back(e);
  }
  w.recv_elements.assign(w.neighbours.size(), {});
  std::size_t at = 0;  // both lists are by rank, and every cross bond puts its rank in both
  for (const auto& [r, e] : read) {
    while (w.neighbours[at] != r) ++at;
    w.recv_elements[at].push_back(e);
  }
}

void FractureSolver::damping_share(std::vector<double>& V, std::size_t width) {
  // The partners' entries of a vector of `width` numbers per element, from their owners.
  DampingWork& w = damping_;
  const std::size_t m = w.neighbours.size();
  if (m == 0) return;
  w.send.resize(m), w.recv.resize(m);
  w.requests.assign(2 * m, MPI_REQUEST_NULL);
  for (std::size_t k = 0; k < m; ++k) {
    w.recv[k].resize(width * w.recv_elements[k].size());
    MPI_Irecv(w.recv[k].data(), static_cast<int>(w.recv[k].size()), MPI_DOUBLE, w.neighbours[k], kDampingTag,
              decomp_.comm(), &w.requests[k]);
  }
  for (std::size_t k = 0; k < m; ++k) {
    w.send[k].clear();
    for (int e : w.send_elements[k])
      w.send[k].insert(w.send[k].end(), &V[width * static_cast<std::size_t>(e)],
                       &V[width * static_cast<std::size_t>(e)] + width);
    MPI_Isend(w.send[k].data(), static_cast<int>(w.send[k].size()), MPI_DOUBLE, w.neighbours[k], kDampingTag,
              decomp_.comm(), &w.requests[m + k]);
  }
  MPI_Waitall(static_cast<int>(w.requests.size()), w.requests.data(), MPI_STATUSES_IGNORE);
  for (std::size_t k = 0; k < m; ++k)
    for (std::size_t a = 0; a < w.recv_elements[k].size(); ++a)
      std::copy(&w.recv[k][width * a], &w.recv[k][width * a] + width,
                &V[width * static_cast<std::size_t>(w.recv_elements[k][a])]);
}

namespace {
// Entry (a, c), c <= a, of a lower triangle stored by rows.
constexpr std::size_t lower(int a, int c) { return static_cast<std::size_t>(a * (a + 1) / 2 + c); }
}  // namespace

void FractureSolver::damping_matrix(double h) {
  const int rank = decomp_.rank();
  const std::vector<int>& owned = owned_by_rank_[static_cast<std::size_t>(rank)];
  const BondLaw& law = settings_.bond;
  DampingWork& w = damping_;
  const std::size_t n = block_.size();
  // Every block made again: the first call, a bond first seen, or another step.
  const bool full = w.h != h;
  w.h = h;
  // B9b: the frozen orientations of the elements read here (owned, and the partners of its bonds)
  // follow them past the angle; every rank holding an element decides alike, from its state alone.
  if (frozen_q_.size() != n) frozen_q_ = q_;
  w.frozen.resize(n);
  w.turned.assign(n, 0);
  const bool exact = settings_.damping_frozen_angle == 0;
  auto follow = [&](std::size_t e) {
    if (w.turned[e]) return;
    const Quaternion &a = q_[e], &b = frozen_q_[e];
    const double c = std::fabs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z);
    const bool moved = exact ? (a.w != b.w || a.x != b.x || a.y != b.y || a.z != b.z) : c < frozen_cos_[e];
    if (moved) frozen_q_[e] = a, w.turned[e] = 1;
    if (moved || full) w.frozen[e] = make_pose({}, {}, {}, frozen_q_[e]);
  };
  for (int e : owned) follow(static_cast<std::size_t>(e));
  for (const DampingLink& k : w.links) {
    if (!k.own_i) follow(static_cast<std::size_t>(k.i));
    if (!k.own_j) follow(static_cast<std::size_t>(k.j));
  }

  // Each link's terms, remade where one of its elements' frozen orientations moved: its terms in the
  // two diagonal blocks (lower triangles) and its block (rows: the master's velocities, columns: the
  // slave's). A unit's J is [1, X] for the slave and -[1, X] for the master, X = -[r]x the map
  // w -> w x r; with D = a' n n^T + a_t 1 (a' = a_n - a_t) and s = r x n (= X^T n):
  // X_a^T D = a' s_a n^T + a_t X_a^T,  X_a^T D X_b = a' s_a s_b^T + a_t ((r_a . r_b) 1 - r_b r_a^T).
  // A link's three units share n, a' and a_t, and s = r x n is linear in r: the blocks need only
  // the sums over the vertices of r, of the products s s^T and r r^T, and of the dot products.
  w.link_remade.assign(w.links.size(), 0);
  for (std::size_t l = 0; l < w.links.size(); ++l) {
    const DampingLink& k = w.links[l];
    const std::size_t s = static_cast<std::size_t>(k.slot), ei = static_cast<std::size_t>(k.i),
                      ej = static_cast<std::size_t>(k.j);
    if (!full && w.live[s] && !w.turned[ei] && !w.turned[ej]) continue;
    w.link_remade[l] = 1, w.live[s] = 1, w.remade[ei] = 1, w.remade[ej] = 1;
    const BondGeometry& g = block_.bonds[static_cast<std::size_t>(k.bond)];
    const Pose &pi = w.frozen[ei], &pj = w.frozen[ej];
    const double share = settings_.damping_theta * h * g.area / 3;
    const double at = share * law.cs, ap = share * law.cn - at;
    const Vec3 nw = pi.rot(g.normal);
    const double n[3] = {nw.x, nw.y, nw.z};
    double ri[3] = {0, 0, 0}, rj[3] = {0, 0, 0}, Sii[3][3] = {}, Sjj[3][3] = {}, Sij[3][3] = {}, Rii[3][3] = {},
           Rjj[3][3] = {}, Rji[3][3] = {};
    for (int v = 0; v < 3; ++v) {
      const Vec3 a = pi.rot(g.at_master[v]), b = pj.rot(g.at_slave[v]);
      const Vec3 si = cross(a, nw), sj = cross(b, nw);
      const double a_[3] = {a.x, a.y, a.z}, b_[3] = {b.x, b.y, b.z};
      const double si_[3] = {si.x, si.y, si.z}, sj_[3] = {sj.x, sj.y, sj.z};
      for (int p = 0; p < 3; ++p) {
        ri[p] += a_[p], rj[p] += b_[p];
        for (int q = 0; q < 3; ++q) {
          Sii[p][q] += si_[p] * si_[q], Sjj[p][q] += sj_[p] * sj_[q], Sij[p][q] += si_[p] * sj_[q];
          Rii[p][q] += a_[p] * a_[q], Rjj[p][q] += b_[p] * b_[q], Rji[p][q] += b_[p] * a_[q];
        }
      }
    }
    const Vec3 si = cross(Vec3{ri[0], ri[1], ri[2]}, nw), sj = cross(Vec3{rj[0], rj[1], rj[2]}, nw);
    const double s_i[3] = {si.x, si.y, si.z}, s_j[3] = {sj.x, sj.y, sj.z};
    const double tii = Rii[0][0] + Rii[1][1] + Rii[2][2], tjj = Rjj[0][0] + Rjj[1][1] + Rjj[2][2],
                 tij = Rji[0][0] + Rji[1][1] + Rji[2][2];
    // X(r) w = w x r; X(r)^T = -X(r).
    auto X = [](const double (&r)[3], int p, int q) {
      const double m[3][3] = {{0, r[2], -r[1]}, {-r[2], 0, r[0]}, {r[1], -r[0], 0}};
      return m[p][q];
    };
    Lower6 &Ti = w.to_i[s], &Tj = w.to_j[s];
    Block6& O = w.off[s];
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) {
        const double id = p == q ? 1.0 : 0.0;
        const double vv = 3 * (ap * n[p] * n[q] + at * id);
        // [1; X_a^T] D [1, X_b] summed over the vertices, for (a, b) = (i, i), (j, j), (i, j).
        const double vw_i = ap * n[p] * s_i[q] + at * X(ri, p, q), vw_j = ap * n[p] * s_j[q] + at * X(rj, p, q);
        const double wv_i = ap * s_i[p] * n[q] - at * X(ri, p, q);  // X_i^T D's (p, q): a' s_i n^T + a_t X_i^T
        const double ww_ii = ap * Sii[p][q] + at * (tii * id - Rii[q][p]);
        const double ww_jj = ap * Sjj[p][q] + at * (tjj * id - Rjj[q][p]);
        const double ww_ij = ap * Sij[p][q] + at * (tij * id - Rji[p][q]);
        // The diagonal blocks' lower triangles: (p, q) and (3 + p, 3 + q) for q <= p, (3 + q, p) all.
        if (q <= p) Ti[lower(p, q)] = vv, Tj[lower(p, q)] = vv, Ti[lower(3 + p, 3 + q)] = ww_ii, Tj[lower(3 + p, 3 + q)] = ww_jj;
        Ti[lower(3 + q, p)] = vw_i, Tj[lower(3 + q, p)] = vw_j;
        O[6 * p + q] = -vv, O[6 * p + 3 + q] = -vw_j, O[6 * (3 + p) + q] = -wv_i, O[6 * (3 + p) + 3 + q] = -ww_ij;
      }
  }

  // Each owned element's diagonal block where one of its terms changed: its mass and world inertia
  // R diag(I) R^T at its frozen orientation, then its intact bonds' terms in bond order (the same
  // order on any rank count), lower triangle only; its Cholesky factor's inverse L^-1 (21 lower
  // entries by rows). The partners' L^-1 from their owners.
  w.diag.resize(n);
  if (w.linv.size() != kTri * n) w.linv.assign(kTri * n, 0.0);
  for (int e : owned) {
    const std::size_t i = static_cast<std::size_t>(e);
    if (!full && !w.remade[i]) continue;
    w.remade[i] = 1;
    const Pose& p = w.frozen[i];
    const Vec3& I = block_.inertia[i];
    Block6& B = w.diag[i];
    B.fill(0.0);
    for (int a = 0; a < 3; ++a) {
      B[6 * a + a] = block_.mass[i];
      for (int c = 0; c < 3; ++c)  // R[a] is row a of body -> world
        B[6 * (3 + a) + 3 + c] = p.R[a].x * I.x * p.R[c].x + p.R[a].y * I.y * p.R[c].y + p.R[a].z * I.z * p.R[c].z;
    }
    for (int k : element_bonds_[i]) {
      if (broken_[static_cast<std::size_t>(k)]) continue;
      const std::size_t s = static_cast<std::size_t>(w.slot[static_cast<std::size_t>(k)]);
      const Lower6& T = block_.bonds[static_cast<std::size_t>(k)].master == e ? w.to_i[s] : w.to_j[s];
      for (int a = 0; a < 6; ++a)
        for (int c = 0; c <= a; ++c) B[static_cast<std::size_t>(6 * a + c)] += T[lower(a, c)];
    }
    const Block6 m = cholesky_inverse(B);
    double* t = &w.linv[kTri * i];
    for (int a = 0; a < 6; ++a)
      for (int c = 0; c <= a; ++c) *t++ = m[static_cast<std::size_t>(6 * a + c)];
  }
  damping_share(w.linv, kTri);

  // The solve in the blocks' own scale (block Jacobi as a change of variables): with each diagonal
  // block D_i = L_i L_i^T, CG on L^-1 (M + theta h C) L^-T, whose diagonal blocks are the identity
  // and whose link blocks are L_i^-1 B L_j^-T, for y = L^T dV from L^-1 b. Its iterates are those of
  // CG preconditioned by the inverse blocks, and it reads no diagonal block or inverse: the link
  // blocks, in single precision, are all the matrix it reads (the impulses use the units). A link's
  // scaled block is remade with its block or either L^-1 (a link across ranks every call: its
  // partner's L^-1 may have changed there), on both ranks of a cross link from the same numbers.
  for (std::size_t l = 0; l < w.links.size(); ++l) {
    const DampingLink& k = w.links[l];
    const std::size_t ei = static_cast<std::size_t>(k.i), ej = static_cast<std::size_t>(k.j);
    if (!w.link_remade[l] && k.own_i && k.own_j && !w.remade[ei] && !w.remade[ej]) continue;
    const double* li = &w.linv[kTri * ei];
    const double* lj = &w.linv[kTri * ej];
    const Block6& O = w.off[static_cast<std::size_t>(k.slot)];
    double T[36];  // L_i^-1 B: row a from B's rows 0..a
    for (int a = 0, t = 0; a < 6; ++a, t += a) {
      for (int c = 0; c < 6; ++c) T[6 * a + c] = 0;
      for (int q = 0; q <= a; ++q)
        for (int c = 0; c < 6; ++c) T[6 * a + c] += li[t + q] * O[static_cast<std::size_t>(6 * q + c)];
    }
    Block6f& F = w.off_f[static_cast<std::size_t>(k.slot)];
    for (int a = 0; a < 6; ++a)
      for (int b = 0, t = 0; b < 6; ++b, t += b) {  // (T L_j^-T)_ab = sum_{c <= b} T_ac (L_j^-1)_bc
        double v = 0;
        for (int c = 0; c <= b; ++c) v += T[6 * a + c] * lj[t + c];
        F[static_cast<std::size_t>(6 * a + b)] = static_cast<float>(v);
      }
  }
}

void FractureSolver::damping_solve() {  // h is folded into the units and the blocks
  const int rank = decomp_.rank();
  const std::vector<int>& owned = owned_by_rank_[static_cast<std::size_t>(rank)];
  DampingWork& w = damping_;
  const std::size_t n = block_.size();
  std::vector<double>&X = w.x, &B = w.b, &R = w.r, &Pd = w.p, &AP = w.ap;
  // Sized once: the passes below write every owned entry and the exchanges every partner's, and
  // nothing reads the rest.
  for (auto* v : {&X, &B, &R, &Pd, &AP, &w.v0})
    if (v->size() != 6 * n) v->assign(6 * n, 0.0);
  // Y = A X on the owned elements, each element's terms in the same order on any rank count (its
  // identity block, then its links in bond order); X's partners' entries are current. A link's
  // block, stored once, gives its master's rows by six row products and its slave's by six axpys
  // over the same rows.
  // Each entry's terms in the order above, summed in registers: y, x and the block may not alias, so
  // the compiler keeps the sums there (read from and written to memory once).
  auto rows6 = [](const Block6f& M, const double* __restrict x, double* __restrict y) {
    double xc[6], acc[6];
    for (int c = 0; c < 6; ++c) xc[c] = x[c];
    for (int a = 0; a < 6; ++a) {
      double t = 0;
      for (int c = 0; c < 6; ++c) t += static_cast<double>(M[static_cast<std::size_t>(6 * a + c)]) * xc[c];
      acc[a] = t;
    }
    for (int a = 0; a < 6; ++a) y[a] += acc[a];
  };
  auto axpy6 = [](const Block6f& M, const double* __restrict x, double* __restrict y) {
    double acc[6];
    for (int a = 0; a < 6; ++a) acc[a] = y[a];
    for (int c = 0; c < 6; ++c) {
      const double xc = x[c];
      for (int a = 0; a < 6; ++a) acc[a] += static_cast<double>(M[static_cast<std::size_t>(6 * c + a)]) * xc;
    }
    for (int a = 0; a < 6; ++a) y[a] = acc[a];
  };
  auto apply = [&](const std::vector<double>& Xv, std::vector<double>& Y) {
    for (int e : owned) {
      const std::size_t i = 6 * static_cast<std::size_t>(e);
      for (int a = 0; a < 6; ++a) Y[i + a] = Xv[i + a];
    }
    for (std::size_t l = 0; l < w.links.size(); ++l) {
      const DampingLink& k = w.links[l];
      const std::size_t i = 6 * static_cast<std::size_t>(k.i), j = 6 * static_cast<std::size_t>(k.j);
      const Block6f& O = w.off_f[static_cast<std::size_t>(k.slot)];
      if (k.own_i) rows6(O, &Xv[j], &Y[i]);  // B X_j: six row products
      if (k.own_j) axpy6(O, &Xv[i], &Y[j]);  // B^T X_i: six axpys over B's rows
    }
  };
  // An inner product over the owned elements: each element's six terms in order, then an exact sum
  // over the elements and the ranks, so every rank count takes the same steps to the same bits.
  auto inner = [&](const std::vector<double>& a, const std::vector<double>& b) {
    ExactSum sum;
    for (int e : owned) {
      const std::size_t i = 6 * static_cast<std::size_t>(e);
      double s = 0;
      for (int c = 0; c < 6; ++c) s += a[i + c] * b[i + c];
      sum.add(s);
    }
    if (decomp_.size() > 1) sum.all_reduce(decomp_.comm());
    return sum.value();
  };
  auto each = [&](auto&& f) {
    for (int e : owned)
      for (std::size_t c = 6 * static_cast<std::size_t>(e); c < 6 * static_cast<std::size_t>(e) + 6; ++c) f(c);
  };
  // The change the dashpots make, dV = V+ - V, solves (M + theta h C) dV = -h C V: its right-hand
  // side is the dashpots' impulses at V, unit by unit in double precision (so the single-precision
  // blocks err relative to the change, not to the velocities).
  const double theta = settings_.damping_theta, c_old = (1 - theta) / theta;
  std::vector<double>& V0 = w.v0;
  for (int e : owned) {
    const std::size_t i = static_cast<std::size_t>(e);
    const double x[6] = {v_[i].x, v_[i].y, v_[i].z, w_[i].x, w_[i].y, w_[i].z};
    std::copy(x, x + 6, &V0[6 * i]);
  }
  damping_share(V0, 6);
  // f(i, j, du, u) for every unit: du its relative velocity at the vector's values.
  auto each_unit = [&](const std::vector<double>& Vv, auto&& f) {
    for (std::size_t l = 0; l < w.links.size(); ++l) {
      const DampingLink& k = w.links[l];
      const double* xi = &Vv[6 * static_cast<std::size_t>(k.i)];
      const double* xj = &Vv[6 * static_cast<std::size_t>(k.j)];
      const Vec3 vi{xi[0], xi[1], xi[2]}, wi{xi[3], xi[4], xi[5]}, vj{xj[0], xj[1], xj[2]}, wj{xj[3], xj[4], xj[5]};
      for (int v = 0; v < 3; ++v) {
        const DampingUnit& u = w.units[3 * l + static_cast<std::size_t>(v)];
        f(k, u, (vj + cross(wj, u.rj)) - (vi + cross(wi, u.ri)));
      }
    }
  };
  auto impulse = [](const DampingUnit& u, const Vec3& du) {  // theta h D du: on i (on j, minus it)
    return u.n * ((u.an - u.at) * dot(du, u.n)) + du * u.at;
  };
  each([&](std::size_t c) { B[c] = 0, X[c] = 0; });
  each_unit(V0, [&](const DampingLink& k, const DampingUnit& u, const Vec3& du) {
    const Vec3 f = impulse(u, du) / theta;
    if (k.own_i) {
      const Vec3 t = cross(u.ri, f);
      double* y = &B[6 * static_cast<std::size_t>(k.i)];
      y[0] += f.x, y[1] += f.y, y[2] += f.z, y[3] += t.x, y[4] += t.y, y[5] += t.z;
    }
    if (k.own_j) {
      const Vec3 t = cross(u.rj, f);
      double* y = &B[6 * static_cast<std::size_t>(k.j)];
      y[0] -= f.x, y[1] -= f.y, y[2] -= f.z, y[3] -= t.x, y[4] -= t.y, y[5] -= t.z;
    }
  });
  // In the scaled variables: R = L^-1 B (from y = 0), and CG stops when the residual's norm is rtol
  // times the right-hand side's, r^T D^-1 r <= rtol^2 b^T D^-1 b in the unscaled ones.
  for (int e : owned) {
    const std::size_t i = 6 * static_cast<std::size_t>(e);
    const double* L = &w.linv[kTri * static_cast<std::size_t>(e)];
    for (int a = 0, t = 0; a < 6; ++a, t += a) {
      double v = 0;
      for (int c = 0; c <= a; ++c) v += L[t + c] * B[i + static_cast<std::size_t>(c)];
      R[i + static_cast<std::size_t>(a)] = v;
    }
  }
  each([&](std::size_t c) { Pd[c] = R[c]; });
  double rr = inner(R, R);
  const double tol2 = settings_.damping_rtol * settings_.damping_rtol * rr;
  int it = 0;
  std::optional<PhaseTimers::Scope> solving(std::in_place, timers_, "damping/cg");  // the iterations alone
  for (; it < kMaxDampingIterations && rr > tol2; ++it) {
    damping_share(Pd, 6);
    apply(Pd, AP);
    const double alpha = rr / inner(Pd, AP);
    // One pass: the update and this element's share of r^T r.
    ExactSum sum;
    for (int e : owned) {
      const std::size_t i = 6 * static_cast<std::size_t>(e);
      double t = 0;
      for (int c = 0; c < 6; ++c) {
        X[i + c] += alpha * Pd[i + c], R[i + c] -= alpha * AP[i + c];
        t += R[i + c] * R[i + c];
      }
      sum.add(t);
    }
    if (decomp_.size() > 1) sum.all_reduce(decomp_.comm());
    const double rr_new = sum.value();
    const double beta = rr_new / rr;
    rr = rr_new;
    each([&](std::size_t c) { Pd[c] = R[c] + beta * Pd[c]; });
  }
  solving.reset();
  if (rr > tol2)
    throw CollectiveRunError("blast: the bond dashpots' solve (docs/theory.md B9a) did not reach blast.damping_rtol in " +
                             std::to_string(kMaxDampingIterations) + " iterations at step " + std::to_string(steps_));
  // Back to the velocities: dV = L^-T y (into B), V+ = V + dV (into X).
  for (int e : owned) {
    const std::size_t i = 6 * static_cast<std::size_t>(e);
    const double* L = &w.linv[kTri * static_cast<std::size_t>(e)];
    double d[6] = {0, 0, 0, 0, 0, 0};
    for (int a = 0, t = 0; a < 6; ++a, t += a)
      for (int c = 0; c <= a; ++c) d[c] += L[t + c] * X[i + static_cast<std::size_t>(a)];
    for (int c = 0; c < 6; ++c) X[i + static_cast<std::size_t>(c)] = d[c];
  }
  damping_iterations_ += it;
  ++damping_solves_;
  // The dashpots' impulses h D (theta du+ + (1 - theta) du) at V+ = V + dV, unit by unit, equal and
  // opposite at the vertex: linear and angular momentum are kept to round-off whatever the residual.
  each([&](std::size_t c) { X[c] += V0[c]; });
  damping_share(X, 6);
  each_unit(X, [&](const DampingLink& k, const DampingUnit& u, const Vec3& du_new) {
    Vec3 du = du_new;
    if (c_old > 0) {
      const double* yi = &V0[6 * static_cast<std::size_t>(k.i)];
      const double* yj = &V0[6 * static_cast<std::size_t>(k.j)];
      du += ((Vec3{yj[0], yj[1], yj[2]} + cross(Vec3{yj[3], yj[4], yj[5]}, u.rj)) -
             (Vec3{yi[0], yi[1], yi[2]} + cross(Vec3{yi[3], yi[4], yi[5]}, u.ri))) * c_old;
    }
    const Vec3 f = impulse(u, du);
    const std::size_t i = static_cast<std::size_t>(k.i), j = static_cast<std::size_t>(k.j);
    if (k.own_i) v_[i] += f / block_.mass[i], L_[i] += cross(u.ri, f);
    if (k.own_j) v_[j] -= f / block_.mass[j], L_[j] -= cross(u.rj, f);
  });
  for (int e : owned) {
    const std::size_t i = static_cast<std::size_t>(e);
    w_[i] = spin(i, q_[i].unrotate(L_[i]));
  }
}

}  // namespace tessera
