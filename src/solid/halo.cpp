// SPDX-License-Identifier: MIT
#include "solid/halo.hpp"

#include <string>
#include <unordered_map>

#include "core/errors.hpp"

namespace tessera {

void Halo::exchange(int send_rank, int recv_rank, const std::vector<double>& out, std::vector<double>& in) {
  MPI_Comm comm = decomp_.comm();
  long n_out = static_cast<long>(out.size()), n_in = 0;
  MPI_Sendrecv(&n_out, 1, MPI_LONG, send_rank, 11, &n_in, 1, MPI_LONG, recv_rank, 11, comm, MPI_STATUS_IGNORE);
  if (recv_rank == MPI_PROC_NULL) n_in = 0;
  in.resize(static_cast<std::size_t>(n_in));
  MPI_Sendrecv(out.data(), static_cast<int>(n_out), MPI_DOUBLE, send_rank, 12, in.data(), static_cast<int>(n_in),
               MPI_DOUBLE, recv_rank, 12, comm, MPI_STATUS_IGNORE);
  if (send_rank != MPI_PROC_NULL) bytes_sent_ += out.size() * sizeof(double);
}

void Halo::migrate(ParticleStore& p, HistoryMap& histories) {
  p.ghosts = 0;
  p.resize(p.owned);
  swaps_.clear();
  const auto& coords = decomp_.coords();
  // Which history entries involve a body: built once, extended with what arrives.
  std::unordered_multimap<std::int64_t, PairKey> by_body;
  bool indexed = false;
  auto index_key = [&](PairKey key) {
    by_body.emplace(key_low(key) / key_stride, key);
    if (key_high(key) < kWallKeyBase) by_body.emplace(key_high(key) / key_stride, key);
  };

  for (int d = 0; d < 3; ++d) {
    if (decomp_.dims()[d] == 1) continue;
    for (int dir = 0; dir < 2; ++dir) {
      const int send_rank = decomp_.neighbor(d, dir), recv_rank = decomp_.neighbor(d, 1 - dir);
      out_.clear();
      std::vector<double> hist_out;
      std::size_t keep = 0;
      for (std::size_t i = 0; i < p.owned; ++i) {
        const int c = decomp_.owner_coord(d, p.x[3 * i + d]);
        const bool leaves = dir == 0 ? c < coords[d] : c > coords[d];
        if (!leaves || send_rank == MPI_PROC_NULL) {
          p.copy(i, keep++);
          continue;
        }
        p.pack(i, out_);
        ++migrations_;
        if (!indexed) {
          by_body.reserve(2 * histories.size());
          for (const auto& [key, h] : histories) index_key(key);
          indexed = true;
        }
        const auto range = by_body.equal_range(p.order[i]);
        for (auto it = range.first; it != range.second; ++it) {
          const auto& h = histories.at(it->second);
          hist_out.push_back(static_cast<double>(it->second >> 32));
          hist_out.push_back(static_cast<double>(it->second & 0xffffffffULL));
          hist_out.insert(hist_out.end(), h.begin(), h.end());
        }
      }
      p.owned = keep;
      p.resize(keep);
      exchange(send_rank, recv_rank, out_, in_);
      const std::size_t stride = static_cast<std::size_t>(p.packed_size());
      for (std::size_t off = 0; off < in_.size(); off += stride) {
        const std::size_t i = p.unpack_append(&in_[off]);
        if (decomp_.owner_coord(d, p.x[3 * i + d]) != coords[d])
          throw RunError("body " + std::to_string(p.id[i]) +
                         " crossed more than one sub-domain between two neighbour-list builds "
                         "(velocity too high for the skin, or sub-domains thinner than the skin)");
      }
      p.owned = p.size();
      exchange(send_rank, recv_rank, hist_out, in_);
      for (std::size_t off = 0; off + 5 <= in_.size(); off += 5) {
        const PairKey key = (static_cast<PairKey>(in_[off]) << 32) | static_cast<PairKey>(in_[off + 1]);
        if (histories.emplace(key, std::array<double, 3>{in_[off + 2], in_[off + 3], in_[off + 4]}).second && indexed)
          index_key(key);
      }
    }
  }
}

void Halo::build_ghosts(ParticleStore& p, double reach_extra) {
  p.ghosts = 0;
  p.resize(p.owned);
  swaps_.clear();
  const Vec3 lo = decomp_.sub_lo(), hi = decomp_.sub_hi();
  for (int d = 0; d < 3; ++d) {
    if (decomp_.dims()[d] == 1) continue;
    const std::size_t candidates = p.size();
    for (int dir = 0; dir < 2; ++dir) {
      Swap s;
      s.dim = d;
      s.send_rank = decomp_.neighbor(d, dir);
      s.recv_rank = decomp_.neighbor(d, 1 - dir);
      out_.clear();
      if (s.send_rank != MPI_PROC_NULL) {
        for (std::size_t i = 0; i < candidates; ++i) {
          const double reach = p.radius[i] + reach_extra;
          if (reach >= hi[d] - lo[d])
            throw RunError("sub-domain width " + std::to_string(hi[d] - lo[d]) + " m along axis " + std::to_string(d) +
                           " is smaller than the interaction reach " + std::to_string(reach) +
                           " m: use fewer ranks along that axis");
          const double xd = p.x[3 * i + d];
          if (dir == 0 ? xd < lo[d] + reach : xd >= hi[d] - reach) {
            s.send.push_back(static_cast<std::int32_t>(i));
            p.pack_ghost(i, out_);
          }
        }
      }
      exchange(s.send_rank, s.recv_rank, out_, in_);
      s.recv_first = p.size();
      s.recv_count = in_.size() / ParticleStore::ghost_size;
      for (std::size_t k = 0; k < s.recv_count; ++k) p.unpack_ghost_append(&in_[k * ParticleStore::ghost_size]);
      p.ghosts += s.recv_count;
      swaps_.push_back(std::move(s));
    }
  }
}

void Halo::forward(ParticleStore& p) {
  MPI_Comm comm = decomp_.comm();
  for (const auto& s : swaps_) {
    const bool rot = forward_orientation;
    const std::size_t stride = ParticleStore::forward_size + (rot ? 4 : 0);
    out_.resize(s.send.size() * stride);
    double* o = out_.data();
    for (const auto i : s.send) {
      for (int k = 0; k < 3; ++k) *o++ = p.x[3 * i + k];
      for (int k = 0; k < 3; ++k) *o++ = p.v[3 * i + k];
      for (int k = 0; k < 3; ++k) *o++ = p.omega[3 * i + k];
      if (rot)
        for (int k = 0; k < 4; ++k) *o++ = p.q[4 * i + k];
    }
    in_.resize(s.recv_count * stride);
    MPI_Sendrecv(out_.data(), static_cast<int>(out_.size()), MPI_DOUBLE, s.send_rank, 13, in_.data(),
                 static_cast<int>(in_.size()), MPI_DOUBLE, s.recv_rank, 13, comm, MPI_STATUS_IGNORE);
    if (s.send_rank != MPI_PROC_NULL) bytes_sent_ += out_.size() * sizeof(double);
    const double* in = in_.data();
    for (std::size_t k = 0; k < s.recv_count; ++k) {
      const std::size_t i = s.recv_first + k;
      for (int c = 0; c < 3; ++c) p.x[3 * i + c] = *in++;
      for (int c = 0; c < 3; ++c) p.v[3 * i + c] = *in++;
      for (int c = 0; c < 3; ++c) p.omega[3 * i + c] = *in++;
      if (rot)
        for (int c = 0; c < 4; ++c) p.q[4 * i + c] = *in++;
    }
  }
}

void Halo::forward_values(std::vector<double>& values, int width) {
  MPI_Comm comm = decomp_.comm();
  const std::size_t w = static_cast<std::size_t>(width);
  for (const auto& s : swaps_) {
    out_.resize(s.send.size() * w);
    for (std::size_t k = 0; k < s.send.size(); ++k)
      for (std::size_t c = 0; c < w; ++c) out_[k * w + c] = values[static_cast<std::size_t>(s.send[k]) * w + c];
    in_.resize(s.recv_count * w);
    MPI_Sendrecv(out_.data(), static_cast<int>(out_.size()), MPI_DOUBLE, s.send_rank, 15, in_.data(),
                 static_cast<int>(in_.size()), MPI_DOUBLE, s.recv_rank, 15, comm, MPI_STATUS_IGNORE);
    if (s.send_rank != MPI_PROC_NULL) bytes_sent_ += out_.size() * sizeof(double);
    std::copy(in_.begin(), in_.end(), values.begin() + static_cast<std::ptrdiff_t>(s.recv_first * w));
  }
}

void Halo::reverse_add(std::vector<double>& values, int width) {
  MPI_Comm comm = decomp_.comm();
  const std::size_t w = static_cast<std::size_t>(width);
  for (auto s = swaps_.rbegin(); s != swaps_.rend(); ++s) {
    out_.assign(values.begin() + static_cast<std::ptrdiff_t>(s->recv_first * w),
                values.begin() + static_cast<std::ptrdiff_t>((s->recv_first + s->recv_count) * w));
    in_.resize(s->send.size() * w);
    MPI_Sendrecv(out_.data(), static_cast<int>(out_.size()), MPI_DOUBLE, s->recv_rank, 14, in_.data(),
                 static_cast<int>(in_.size()), MPI_DOUBLE, s->send_rank, 14, comm, MPI_STATUS_IGNORE);
    if (s->recv_rank != MPI_PROC_NULL) bytes_sent_ += out_.size() * sizeof(double);
    if (s->send_rank == MPI_PROC_NULL) continue;
    for (std::size_t k = 0; k < s->send.size(); ++k)
      for (std::size_t c = 0; c < w; ++c) values[static_cast<std::size_t>(s->send[k]) * w + c] += in_[k * w + c];
  }
}

}  // namespace tessera
