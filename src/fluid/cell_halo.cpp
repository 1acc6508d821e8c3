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
  // Every offset o in {-1, 0, 1}^3 whose ghosts have a source (a face; with the box stencil an edge
  // or a corner too): this rank sends its owned cells on side o to the rank at o, which writes them
  // into its ghosts on side -o; it receives the ghosts on side o from the rank at o. Offsets are
  // numbered (o_x + 1) + 3 (o_y + 1) + 9 (o_z + 1); -o has number 26 minus o's.
  struct Item {
    int rank, order;
    Box box;
  };
  std::vector<Item> sends, recvs;
  for (int o2 = -1; o2 <= 1; ++o2)
    for (int o1 = -1; o1 <= 1; ++o1)
      for (int o0 = -1; o0 <= 1; ++o0) {
        const std::array<int, 3> o{o0, o1, o2};
        const int nonzero = (o0 != 0) + (o1 != 0) + (o2 != 0);
        if (nonzero == 0 || (stencil == Stencil::star && nonzero > 1)) continue;
        std::array<int, 3> c = b.coords;
        Box send, recv;
        bool source = true;
        for (int d = 0; d < 3; ++d) {
          const int own_lo = b.s[d] - b.gs[d], own_hi = own_lo + b.m[d];
          if (o[d] == 0) {
            send.lo[d] = recv.lo[d] = own_lo;
            send.hi[d] = recv.hi[d] = own_hi;
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
        const int number = (o0 + 1) + 3 * (o1 + 1) + 9 * (o2 + 1);
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
  for (std::size_t k = 0; k < sends.size(); ++k) {
    if (peers_.empty() || peers_.back().rank != sends[k].rank) peers_.push_back({sends[k].rank, {}, {}, 0, 0});
    Peer& P = peers_.back();
    P.send.push_back(sends[k].box);
    P.recv.push_back(recvs[k].box);  // the same peers, the same count per peer: -o's rank is o's
    P.send_size += sends[k].box.size();
    P.recv_size += recvs[k].box.size();
  }
  // Each message's length agreed once with its receiver (a mismatch would be a decomposition the
  // two ranks see differently).
  std::vector<unsigned long> told(peers_.size()), expected(peers_.size());
  std::vector<MPI_Request> req;
  for (std::size_t p = 0; p < peers_.size(); ++p) {
    told[p] = peers_[p].send_size, expected[p] = peers_[p].recv_size;
    if (peers_[p].rank == me_) continue;
    req.emplace_back();
    MPI_Irecv(&told[p], 1, MPI_UNSIGNED_LONG, peers_[p].rank, 1, comm_, &req.back());
    req.emplace_back();
    MPI_Isend(&peers_[p].send_size, 1, MPI_UNSIGNED_LONG, peers_[p].rank, 1, comm_, &req.back());
  }
  MPI_Waitall(int(req.size()), req.data(), MPI_STATUSES_IGNORE);
  for (std::size_t p = 0; p < peers_.size(); ++p)
    if (told[p] != expected[p])
      throw RunError("halo: rank " + std::to_string(peers_[p].rank) + " sends " + std::to_string(told[p]) +
                     " ghost cells where rank " + std::to_string(me_) + " expects " + std::to_string(expected[p]));
  send_buf_.resize(peers_.size());
  recv_buf_.resize(peers_.size());
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
  requests_.clear();
  for (std::size_t p = 0; p < peers_.size(); ++p) {
    const Peer& P = peers_[p];
    if (P.rank == me_) continue;
    recv_buf_[p].resize(P.recv_size * nf);
    requests_.emplace_back();
    MPI_Irecv(recv_buf_[p].data(), int(recv_buf_[p].size()), MPI_DOUBLE, P.rank, 0, comm_, &requests_.back());
  }
  for (std::size_t p = 0; p < peers_.size(); ++p) {
    const Peer& P = peers_[p];
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
  for (std::size_t p = 0; p < peers_.size(); ++p) {
    const Peer& P = peers_[p];
    if (P.rank == me_) continue;
    const double* in = recv_buf_[p].data();
    for (auto* f : fields)
      for (const Box& box : P.recv) {
        unpack(box, *f, in);
        in += box.size();
      }
  }
}

template void CellHalo::exchange_fields(std::initializer_list<std::vector<double>*>) const;
template void CellHalo::exchange_fields(std::initializer_list<std::vector<float>*>) const;

}  // namespace tessera
