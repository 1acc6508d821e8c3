// SPDX-License-Identifier: MIT
#include "fluid/cell_halo.hpp"

#include <algorithm>
#include <cstring>
#include <string>
#include <tuple>
#include <type_traits>

#include "core/errors.hpp"

namespace tessera {

CellHalo::CellHalo(MPI_Comm comm, const Block& b, int width, Stencil stencil) {
  MPI_Comm_dup(comm, &comm_);
  MPI_Comm_rank(comm_, &me_);
  stride_ = {1, b.gm[0], std::ptrdiff_t(b.gm[0]) * b.gm[1]};
  auto rank_of = [&](std::array<int, 3> c) { return c[0] + b.procs[0] * (c[1] + b.procs[1] * c[2]); };
  // The neighbour's coordinate on each side of each direction in the process grid (-1: a wall or
  // an outflow lies there).
  std::array<std::array<int, 2>, 3> nb{};
  for (int d = 0; d < 3; ++d) {
    for (int side = 0; side < 2; ++side) {
      int c = b.coords[d] + (side ? 1 : -1);
      if (c < 0 || c >= b.procs[d]) c = b.periodic[d] ? (c + b.procs[d]) % b.procs[d] : -1;
      nb[d][side] = c;
      fills_[d][side] = c >= 0;
      active_ = active_ || c >= 0;
    }
    if (width > b.m[d] && (fills_[d][0] || fills_[d][1]))
      throw RunError("halo: a block of " + std::to_string(b.m[d]) + " cells along " + "xyz"[d] +
                     " cannot fill ghost layers " + std::to_string(width) + " deep");
  }
  // The offsets o in {-1, 0, 1}^3 whose ghosts have a source: this rank sends its owned cells on
  // side o to the rank at o, which writes them into its ghosts on side -o, and receives the ghosts
  // on side o from the rank at o. Offsets are numbered (o_x + 1) + 3 (o_y + 1) + 9 (o_z + 1); -o
  // has number 26 minus o's. The star stencil: the six faces in one round. The box stencil: one
  // round per direction, its two faces, each box reaching over the ghosts the earlier rounds
  // filled (so edges and corners arrive in two or three hops; straight messages to the diagonal
  // ranks instead, tried 2026-12-05, cost more than the rounds they save where each message's
  // overhead is a third of the latency, as on this host: docs/performance.md).
  struct Item {
    int rank, order;
    Box box;
  };
  // `along`: the round's direction, whose box reaches over the ghosts of the directions before it
  // (box stencil), or -1 (star: every face at once, owned cells only).
  auto round_of = [&](const std::vector<std::array<int, 3>>& offsets, int along) {
    std::vector<Item> sends, recvs;
    for (const auto& o : offsets) {
      std::array<int, 3> c = b.coords;
      Box send, recv;
      bool source = true;
      for (int d = 0; d < 3; ++d) {
        const int own_lo = b.s[d] - b.gs[d], own_hi = own_lo + b.m[d];
        if (o[d] == 0) {
          int lo = own_lo, hi = own_hi;
          if (d < along) {
            if (fills_[d][0]) lo -= width;
            if (fills_[d][1]) hi += width;
          }
          send.lo[d] = recv.lo[d] = lo;
          send.hi[d] = recv.hi[d] = hi;
          continue;
        }
        const int side = o[d] > 0 ? 1 : 0;
        if (!fills_[d][side]) {
          source = false;
          break;
        }
        c[d] = nb[d][side];
        send.lo[d] = side ? own_hi - width : own_lo;
        send.hi[d] = side ? own_hi : own_lo + width;
        recv.lo[d] = side ? own_hi : own_lo - width;
        recv.hi[d] = side ? own_hi + width : own_lo;
        if (recv.lo[d] < 0 || recv.hi[d] > b.gm[d])
          throw RunError(std::string("halo: ghost layers beyond the ghosted box along ") + "xyz"[d]);
      }
      if (!source) continue;  // a wall or an outflow lies that way
      const int number = (o[0] + 1) + 3 * (o[1] + 1) + 9 * (o[2] + 1);
      sends.push_back({rank_of(c), number, send});
      recvs.push_back({rank_of(c), 26 - number, recv});  // the sender's offset is -o
    }
    // One peer per rank, other ranks in rank order and this rank last; each list in the sender's
    // order of the offsets, so the k-th box sent is the k-th box written.
    auto by_rank = [&](const Item& x, const Item& y) {
      const bool xs = x.rank == me_, ys = y.rank == me_;
      return std::tie(xs, x.rank, x.order) < std::tie(ys, y.rank, y.order);
    };
    std::sort(sends.begin(), sends.end(), by_rank);
    std::sort(recvs.begin(), recvs.end(), by_rank);
    std::vector<Peer> peers;
    for (std::size_t k = 0; k < sends.size(); ++k) {
      if (peers.empty() || peers.back().rank != sends[k].rank) peers.push_back({sends[k].rank, {}, {}, 0, 0});
      Peer& P = peers.back();
      P.send.push_back(sends[k].box);
      P.recv.push_back(recvs[k].box);  // the same peers, the same count per peer: -o's rank is o's
      P.send_size += sends[k].box.size();
      P.recv_size += recvs[k].box.size();
    }
    if (!peers.empty()) rounds_.push_back(std::move(peers));
  };
  if (stencil == Stencil::star) {
    round_of({{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}}, -1);
  } else {
    round_of({{-1, 0, 0}, {1, 0, 0}}, 0);
    round_of({{0, -1, 0}, {0, 1, 0}}, 1);
    round_of({{0, 0, -1}, {0, 0, 1}}, 2);
  }
  // Each message's length agreed once with its receiver (a mismatch would be a decomposition the
  // two ranks see differently).
  for (const auto& peers : rounds_) {
    std::vector<unsigned long> told(peers.size()), expected(peers.size());
    std::vector<MPI_Request> req;
    for (std::size_t p = 0; p < peers.size(); ++p) {
      told[p] = peers[p].send_size, expected[p] = peers[p].recv_size;
      if (peers[p].rank == me_) continue;
      req.emplace_back();
      MPI_Irecv(&told[p], 1, MPI_UNSIGNED_LONG, peers[p].rank, 1, comm_, &req.back());
      req.emplace_back();
      MPI_Isend(&peers[p].send_size, 1, MPI_UNSIGNED_LONG, peers[p].rank, 1, comm_, &req.back());
    }
    MPI_Waitall(int(req.size()), req.data(), MPI_STATUSES_IGNORE);
    for (std::size_t p = 0; p < peers.size(); ++p)
      if (told[p] != expected[p])
        throw RunError("halo: rank " + std::to_string(peers[p].rank) + " sends " + std::to_string(told[p]) +
                       " ghost cells where rank " + std::to_string(me_) + " expects " + std::to_string(expected[p]));
    if (peers.size() > send_buf_.size()) send_buf_.resize(peers.size()), recv_buf_.resize(peers.size());
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

template <class T>
void CellHalo::pack(const Box& b, const std::vector<T>& f, double* out) const {
  for_rows(b, [&](std::ptrdiff_t c, std::size_t n) {
    if constexpr (std::is_same_v<T, double>)
      std::memcpy(out, f.data() + c, n * sizeof(double));
    else
      std::copy(f.data() + c, f.data() + c + n, out);
    out += n;
  });
}

template <class T>
void CellHalo::unpack(const Box& b, std::vector<T>& f, const double* in) const {
  for_rows(b, [&](std::ptrdiff_t c, std::size_t n) {
    if constexpr (std::is_same_v<T, double>)
      std::memcpy(f.data() + c, in, n * sizeof(double));
    else
      for (std::size_t i = 0; i < n; ++i) f[std::size_t(c) + i] = T(in[i]);
    in += n;
  });
}

template <class T>
void CellHalo::exchange_fields(std::initializer_list<std::vector<T>*> fields) const {
  if (!active_) return;
  const std::size_t nf = fields.size();
  for (const auto& peers : rounds_) {
    requests_.clear();
    for (std::size_t p = 0; p < peers.size(); ++p) {
      const Peer& P = peers[p];
      if (P.rank == me_) continue;
      recv_buf_[p].resize(P.recv_size * nf);
      requests_.emplace_back();
      MPI_Irecv(recv_buf_[p].data(), int(recv_buf_[p].size()), MPI_DOUBLE, P.rank, 0, comm_, &requests_.back());
    }
    for (std::size_t p = 0; p < peers.size(); ++p) {
      const Peer& P = peers[p];
      std::vector<double>& buf = send_buf_[p];
      buf.resize(P.send_size * nf);
      double* out = buf.data();
      for (auto* f : fields)
        for (const Box& box : P.send) {
          pack(box, *f, out);
          out += box.size();
        }
      if (P.rank == me_) {  // periodic images of this rank's own cells, in the same order
        const double* in = buf.data();
        for (auto* f : fields)
          for (const Box& box : P.recv) {
            unpack(box, *f, in);
            in += box.size();
          }
        continue;
      }
      requests_.emplace_back();
      MPI_Isend(buf.data(), int(buf.size()), MPI_DOUBLE, P.rank, 0, comm_, &requests_.back());
      ++traffic_.messages;
      traffic_.bytes += double(buf.size() * sizeof(double));
    }
    MPI_Waitall(int(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
    for (std::size_t p = 0; p < peers.size(); ++p) {
      const Peer& P = peers[p];
      if (P.rank == me_) continue;
      const double* in = recv_buf_[p].data();
      for (auto* f : fields)
        for (const Box& box : P.recv) {
          unpack(box, *f, in);
          in += box.size();
        }
    }
  }
}

template void CellHalo::exchange_fields(std::initializer_list<std::vector<double>*>) const;
template void CellHalo::exchange_fields(std::initializer_list<std::vector<float>*>) const;

}  // namespace tessera
