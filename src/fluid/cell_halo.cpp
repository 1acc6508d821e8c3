// SPDX-License-Identifier: MIT
#include "fluid/cell_halo.hpp"

#include <algorithm>
#include <cstring>
#include <string>

#include "core/errors.hpp"

namespace tessera {

CellHalo::CellHalo(MPI_Comm comm, const Block& b, int width, Stencil stencil) {
  MPI_Comm_dup(comm, &comm_);
  MPI_Comm_rank(comm_, &me_);
  stride_ = {1, b.gm[0], std::ptrdiff_t(b.gm[0]) * b.gm[1]};
  auto rank_of = [&](std::array<int, 3> c) { return c[0] + b.procs[0] * (c[1] + b.procs[1] * c[2]); };
  // The neighbour rank on each side of each direction (-1: none), in the process grid.
  std::array<std::array<int, 2>, 3> nb{};
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      std::array<int, 3> c = b.coords;
      c[d] += side ? 1 : -1;
      if (c[d] < 0 || c[d] >= b.procs[d]) {
        if (!b.periodic[d]) {
          nb[d][side] = -1;
          continue;
        }
        c[d] = (c[d] + b.procs[d]) % b.procs[d];
      }
      nb[d][side] = rank_of(c);
      active_ = true;
    }
  for (int d = 0; d < 3; ++d) {
    if (width > b.m[d] && (nb[d][0] >= 0 || nb[d][1] >= 0))
      throw RunError("halo: a block of " + std::to_string(b.m[d]) + " cells along " + "xyz"[d] +
                     " cannot fill ghost layers " + std::to_string(width) + " deep");
    for (int side = 0; side < 2; ++side) {
      Side& S = sides_[d][side];
      S.rank = nb[d][side];
      if (S.rank < 0) continue;
      // Local indices: the owned box starts at s - gs.
      for (int e = 0; e < 3; ++e) {
        int lo = b.s[e] - b.gs[e], hi = lo + b.m[e];
        if (e < d && stencil == Stencil::box) {  // the ghosts the earlier directions filled
          if (nb[e][0] >= 0) lo -= width;
          if (nb[e][1] >= 0) hi += width;
        }
        S.send.lo[e] = S.recv.lo[e] = lo;
        S.send.hi[e] = S.recv.hi[e] = hi;
      }
      const int own_lo = b.s[d] - b.gs[d], own_hi = own_lo + b.m[d];
      if (side == 0) {
        S.send.lo[d] = own_lo;
        S.send.hi[d] = own_lo + width;
        S.recv.lo[d] = own_lo - width;
        S.recv.hi[d] = own_lo;
      } else {
        S.send.lo[d] = own_hi - width;
        S.send.hi[d] = own_hi;
        S.recv.lo[d] = own_hi;
        S.recv.hi[d] = own_hi + width;
      }
      for (int e = 0; e < 3; ++e)
        if (S.recv.lo[e] < 0 || S.recv.hi[e] > b.gm[e])
          throw RunError(std::string("halo: ghost layers beyond the ghosted box along ") + "xyz"[e]);
    }
  }
}

CellHalo::~CellHalo() {
  if (comm_ != MPI_COMM_NULL) MPI_Comm_free(&comm_);
}

template <class F>
void CellHalo::for_rows(const Box& b, F&& fn) const {
  const std::size_t row = std::size_t(b.hi[0] - b.lo[0]);
  for (int k = b.lo[2]; k < b.hi[2]; ++k)
    for (int j = b.lo[1]; j < b.hi[1]; ++j) fn(b.lo[0] + j * stride_[1] + k * stride_[2], row);
}

void CellHalo::pack(const Box& b, const std::vector<double>& f, double* out) const {
  for_rows(b, [&](std::ptrdiff_t c, std::size_t n) {
    std::memcpy(out, f.data() + c, n * sizeof(double));
    out += n;
  });
}

void CellHalo::unpack(const Box& b, std::vector<double>& f, const double* in) const {
  for_rows(b, [&](std::ptrdiff_t c, std::size_t n) {
    std::memcpy(f.data() + c, in, n * sizeof(double));
    in += n;
  });
}

void CellHalo::exchange(std::initializer_list<std::vector<double>*> fields) const {
  if (!active_) return;
  const std::size_t nf = fields.size();
  for (int d = 0; d < 3; ++d) {
    // A message travelling towards +d carries tag 2d + 1, towards -d tag 2d: on two ranks along
    // a periodic direction both sides' neighbour is the same rank, and the tags tell them apart.
    MPI_Request req[4];
    int nreq = 0;
    for (int side = 0; side < 2; ++side) {
      const Side& S = sides_[d][side];
      if (S.rank < 0 || S.rank == me_) continue;
      recv_buf_[side].resize(S.recv.size() * nf);
      MPI_Irecv(recv_buf_[side].data(), int(recv_buf_[side].size()), MPI_DOUBLE, S.rank, 2 * d + (side ? 0 : 1),
                comm_, &req[nreq++]);
    }
    for (int side = 0; side < 2; ++side) {
      const Side& S = sides_[d][side];
      if (S.rank < 0) continue;
      if (S.rank == me_) {
        // One rank along a periodic direction: the far side's owned layers are this side's ghosts.
        const Side& far = sides_[d][1 - side];
        send_buf_[side].resize(far.send.size());
        for (auto* f : fields) {
          pack(far.send, *f, send_buf_[side].data());
          unpack(S.recv, *f, send_buf_[side].data());
        }
        continue;
      }
      const std::size_t n = S.send.size();
      send_buf_[side].resize(n * nf);
      std::size_t at = 0;
      for (auto* f : fields) {
        pack(S.send, *f, send_buf_[side].data() + at);
        at += n;
      }
      MPI_Isend(send_buf_[side].data(), int(send_buf_[side].size()), MPI_DOUBLE, S.rank, 2 * d + side, comm_,
                &req[nreq++]);
      ++traffic_.messages;
      traffic_.bytes += double(send_buf_[side].size() * sizeof(double));
    }
    MPI_Waitall(nreq, req, MPI_STATUSES_IGNORE);
    for (int side = 0; side < 2; ++side) {
      const Side& S = sides_[d][side];
      if (S.rank < 0 || S.rank == me_) continue;
      const std::size_t n = S.recv.size();
      std::size_t at = 0;
      for (auto* f : fields) {
        unpack(S.recv, *f, recv_buf_[side].data() + at);
        at += n;
      }
    }
  }
}

}  // namespace tessera
