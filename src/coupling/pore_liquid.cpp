// SPDX-License-Identifier: MIT
#include "coupling/pore_liquid.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace tessera {

namespace {

inline double fluid_part(double alpha) { return std::max(0.0, 1.0 - alpha); }

// How a cell's excess is shared among its face neighbours: first into their room (or out of their
// liquid, for a negative excess), then what is left passes through with the flow, by fluid part
// where the flow does not move, or equally.
enum Mode : unsigned char { kRoom = 0, kFlow = 1, kFluidPart = 2, kEqual = 3 };

// A neighbour's room (a positive excess) or liquid (a negative one).
inline double weight(Mode, bool give, double c, double e) { return give ? std::max(e - c, 0.0) : std::clamp(c, 0.0, e); }

}  // namespace

PoreLiquid::PoreLiquid(const FluidGrid& grid)
    : grid_(grid), c_(grid.make_field()), phi_old_(grid.make_field()), excess_(grid.make_field()),
      share_(grid.make_field()), share2_(grid.make_field()), alpha_old_(grid.make_field()), mode_(grid.local_size(), 0) {}

void PoreLiquid::start(const FlowSolver& flow, const std::vector<double>& alpha) {
  const auto& f = flow.fraction();
  for (std::size_t i = 0; i < c_.size(); ++i) c_[i] = f[i] * std::min(1.0, fluid_part(alpha[i]));
}

void PoreLiquid::before_flow(const FlowSolver& flow) { phi_old_ = flow.fraction(); }

void PoreLiquid::after_flow(const FlowSolver& flow) {
  const auto& f = flow.fraction();
  // Where c and phi are the same number (no body in the cell), c takes phi's new value itself: the
  // same number as c + (phi_new - phi_old) up to the last bit, and the plain VOF bit for bit.
  for (std::size_t i = 0; i < c_.size(); ++i) c_[i] = c_[i] == phi_old_[i] ? f[i] : c_[i] + (f[i] - phi_old_[i]);
}

// A box of global cell indices [lo, hi), possibly empty.
struct PoreLiquid::Box {
  std::array<int, 3> lo{0, 0, 0}, hi{0, 0, 0};
  bool empty() const { return lo[0] >= hi[0] || lo[1] >= hi[1] || lo[2] >= hi[2]; }
  Box grown(int n) const { return {{lo[0] - n, lo[1] - n, lo[2] - n}, {hi[0] + n, hi[1] + n, hi[2] + n}}; }
  Box clipped(const Box& o) const {
    Box b;
    for (int d = 0; d < 3; ++d) b.lo[d] = std::max(lo[d], o.lo[d]), b.hi[d] = std::min(hi[d], o.hi[d]);
    return b;
  }
  void add(int i, int j, int k) {
    if (empty()) {
      lo = {i, j, k}, hi = {i + 1, j + 1, k + 1};
      return;
    }
    const int p[3] = {i, j, k};
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d] + 1);
  }
  template <class F>
  void for_each(F&& fn) const {
    for (int k = lo[2]; k < hi[2]; ++k)
      for (int j = lo[1]; j < hi[1]; ++j)
        for (int i = lo[0]; i < hi[0]; ++i) fn(i, j, k);
  }
};

namespace {

using Box = PoreLiquid::Box;

Box owned_box(const FluidGrid& g) { return {{g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)}}; }
Box domain_box(const FluidGrid& g) { return {{0, 0, 0}, {g.cells()[0], g.cells()[1], g.cells()[2]}}; }
Box ghosted_box(const FluidGrid& g) {
  return {{g.gbegin(0), g.gbegin(1), g.gbegin(2)}, {g.gend(0), g.gend(1), g.gend(2)}};
}

// The ghost cells inside the domain: the ghosted box less the owned one, slab by slab.
template <class F>
void for_each_ghost(const FluidGrid& g, F&& fn) {
  const Box own = owned_box(g), all = ghosted_box(g).clipped(domain_box(g));
  for (int k = all.lo[2]; k < all.hi[2]; ++k)
    for (int j = all.lo[1]; j < all.hi[1]; ++j) {
      const bool row_owned = k >= own.lo[2] && k < own.hi[2] && j >= own.lo[1] && j < own.hi[1];
      for (int i = all.lo[0]; i < all.hi[0]; ++i) {
        if (row_owned && i == own.lo[0]) i = own.hi[0];
        if (i >= all.hi[0]) break;
        fn(i, j, k);
      }
    }
}

}  // namespace

// One Jacobi pass over the cells within one cell of `active` (the cells with an excess, owned or
// ghost): every one of them hands its excess to its face neighbours in the domain.
void PoreLiquid::pass(const std::vector<double>& alpha, const Box& active, int sign) {
  const FluidGrid& g = grid_;
  const std::ptrdiff_t s[3] = {g.stride(0), g.stride(1), g.stride(2)};
  const Box domain = domain_box(g);
  auto inside = [&](const int n[3]) {
    return n[0] >= 0 && n[1] >= 0 && n[2] >= 0 && n[0] < domain.hi[0] && n[1] < domain.hi[1] && n[2] < domain.hi[2];
  };
  const bool give = sign > 0;
  auto sends = [&](std::size_t c) { return give ? excess_[c] > 0 : excess_[c] < 0; };
  // The face speed from cell c towards its neighbour on `side` of direction d.
  auto towards = [&](std::size_t c, int d, int side) { return side > 0 ? uf_[d][c + s[d]] : -uf_[d][c]; };
  // How much of what passes through a sender goes to a neighbour: a positive excess goes with the
  // flow out of the cell, a negative one is drawn from where the flow came in (the liquid the flow
  // moved continues with it); where the flow does not move, by fluid part, or equally.
  auto through = [&](Mode m, double speed_out, double e) {
    if (m == kFlow) return std::max(give ? speed_out : -speed_out, 0.0);
    return m == kFluidPart ? e : 1.0;
  };
  // Senders: the owned cells and one ghost layer (the owned cells' neighbours); their weights need
  // the neighbours of those, which the two ghost layers hold. A sender fills its neighbours' room
  // (empties their liquid, for a negative excess) in proportion to it, each at most to the brim;
  // the rest passes through.
  const Box senders = active.clipped(owned_box(g).grown(1)).clipped(domain);
  senders.for_each([&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    share_[c] = share2_[c] = 0;
    if (!sends(c)) return;
    const double x = std::abs(excess_[c]);
    const int ijk[3] = {i, j, k};
    double room = 0, w[3] = {0, 0, 0};
    for (int d = 0; d < 3; ++d)
      for (int side = -1; side <= 1; side += 2) {
        int n[3] = {ijk[0], ijk[1], ijk[2]};
        n[d] += side;
        if (!inside(n)) continue;
        const std::size_t nb = c + side * s[d];
        const double e = fluid_part(alpha[nb]);
        room += weight(kRoom, give, c_[nb], e);
        for (Mode m : {kFlow, kFluidPart, kEqual}) w[m - 1] += through(m, towards(c, d, side), e);
      }
    const double fill = std::min(x, room), rest = x - fill;
    if (room > 0) share_[c] = sign * fill / room;
    if (rest > 0)
      for (Mode m : {kFlow, kFluidPart, kEqual})
        if (w[m - 1] > 0) {
          mode_[c] = m;
          share2_[c] = sign * rest / w[m - 1];
          break;
        }
  });
  // Receivers: each owned cell gives its excess if it sends and takes its shares of its neighbours'.
  const Box receivers = active.grown(1).clipped(owned_box(g));
  auto in_senders = [&](const int n[3]) {
    return senders.lo[0] <= n[0] && n[0] < senders.hi[0] && senders.lo[1] <= n[1] && n[1] < senders.hi[1] &&
           senders.lo[2] <= n[2] && n[2] < senders.hi[2];
  };
  next_.clear();
  receivers.for_each([&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    const double e = fluid_part(alpha[c]);
    double in = 0;
    const int ijk[3] = {i, j, k};
    for (int d = 0; d < 3; ++d)
      for (int side = -1; side <= 1; side += 2) {
        int n[3] = {ijk[0], ijk[1], ijk[2]};
        n[d] += side;
        if (!inside(n) || !in_senders(n)) continue;
        const std::size_t nb = c + side * s[d];
        if (share_[nb] != 0) in += share_[nb] * weight(kRoom, give, c_[c], e);
        // The face from the sender towards this cell is this cell's face on `side`, reversed.
        if (share2_[nb] != 0) in += share2_[nb] * through(Mode(mode_[nb]), -towards(c, d, side), e);
      }
    next_.push_back(c_[c] - (sends(c) ? excess_[c] : 0.0) + in);
  });
  std::size_t n = 0;
  receivers.for_each([&](int i, int j, int k) { c_[g.at(i, j, k)] = next_[n++]; });
}

void PoreLiquid::displace(const BodyMoves& moves, std::size_t slots,
                          const std::function<void(std::vector<double>&)>& complete) {
  const double cell_volume = grid_.cell_volume();
  // Per cell: the volume the bodies entered, and the liquid per entered volume taken out with it
  // (the cell's liquid share c / e before the move, at most what the cell holds).
  entered_.assign(c_.size(), 0.0);
  for (std::size_t e = 0; e < moves.dv.size(); ++e) entered_[moves.cell[e]] += std::max(moves.dv[e], 0.0);
  auto taken_per_volume = [&](std::size_t c) {
    const double room = fluid_part(alpha_old_[c]) * cell_volume, in = entered_[c];
    if (room <= 0 || in <= 0) return 0.0;
    return std::clamp(c_[c], 0.0, 1.0) * cell_volume / std::max(room, in);
  };
  sums_.assign(2 * slots, 0.0);
  for (std::size_t n = 0; n < moves.body.size(); ++n) {
    double* s = &sums_[2 * moves.body[n]];
    for (std::size_t e = moves.first[n]; e < moves.first[n + 1]; ++e) {
      const double dv = moves.dv[e];
      if (dv > 0)
        s[0] += taken_per_volume(moves.cell[e]) * dv;  // liquid taken
      else
        s[1] -= dv;  // volume left
    }
  }
  complete(sums_);
  std::vector<double> next(c_);
  for (std::size_t n = 0; n < moves.body.size(); ++n) {
    const double* s = &sums_[2 * moves.body[n]];
    for (std::size_t e = moves.first[n]; e < moves.first[n + 1]; ++e) {
      const std::size_t c = moves.cell[e];
      const double dv = moves.dv[e];
      if (dv > 0)
        next[c] -= taken_per_volume(c) * dv / cell_volume;
      else if (s[1] > 0)
        next[c] += s[0] * (-dv / s[1]) / cell_volume;
    }
  }
  c_.swap(next);
}

PoreLiquidStats PoreLiquid::settle(FlowSolver& flow, const std::vector<double>& alpha) {
  const FluidGrid& g = grid_;
  PoreLiquidStats st;
  const Box own = owned_box(g), domain = domain_box(g);
  Box active;  // the cells (owned or ghost) with an excess
  double worst = 0, total = 0, most = 0, least = 0;
  auto measure = [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    const double x = c_[c] - std::clamp(c_[c], 0.0, fluid_part(alpha[c]));
    excess_[c] = std::abs(x) > kTolerance ? x : 0.0;
    if (excess_[c] != 0) active.add(i, j, k);
    if (i >= own.lo[0] && i < own.hi[0] && j >= own.lo[1] && j < own.hi[1] && k >= own.lo[2] && k < own.hi[2])
      worst = std::max(worst, std::abs(x)), total += std::abs(excess_[c]), most = std::max(most, excess_[c]),
      least = std::min(least, excess_[c]);
  };
  g.exchange(c_);
  std::fill(excess_.begin(), excess_.end(), 0.0);
  ghosted_box(g).clipped(domain).for_each(measure);
  st.displaced = g.reduce_sum(total) * g.cell_volume();
  for (;; ++st.passes) {
    worst = g.reduce_max(worst);
    st.residual = worst;
    if (worst <= kTolerance || st.passes >= kMaxPasses) break;
    // Positive and negative excesses move in turn (both at once, a pair of cells with opposite
    // excesses would swap them for ever); a sign that has none anywhere gives its turn away.
    most = g.reduce_max(most), least = g.reduce_min(least);
    const int sign = (st.passes % 2 == 0 && most > 0) || least == 0 ? 1 : -1;
    if (st.passes == 0) {  // the flow's face speeds, with the ghost cells' faces
      for (int d = 0; d < 3; ++d) uf_[d] = flow.face_velocity(d);
      g.exchange({&uf_[0], &uf_[1], &uf_[2]});
    }
    const Box was = active;
    pass(alpha, was, sign);
    g.exchange(c_);
    // Owned cells change only within one cell of the active ones; ghosts anywhere in the layers.
    for (const Box& b : {was, was.grown(1).clipped(own)}) b.clipped(ghosted_box(g)).for_each([&](int i, int j, int k) {
      excess_[g.at(i, j, k)] = 0;
    });
    active = Box{};
    worst = most = least = 0;
    was.grown(1).clipped(own).for_each(measure);
    for_each_ghost(g, measure);
  }
  // The flow's liquid fraction: the liquid share of the fluid part, the advected (virtual) value
  // taking over where the fluid part is small.
  auto& f = flow.mutable_fraction();
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) {
        const std::size_t c = g.at(i, j, k);
        const double e = fluid_part(alpha[c]);
        double phi;
        if (e >= 1)
          phi = c_[c];
        else if (e >= kMinFluidPart)
          phi = c_[c] / e;
        else
          phi = (c_[c] + (kMinFluidPart - e) * f[c]) / kMinFluidPart;
        f[c] = std::clamp(phi, 0.0, 1.0);
      }
  flow.fraction_changed();
  alpha_old_ = alpha;
  last_ = st;
  return st;
}

double PoreLiquid::volume() const { return grid_.sum_owned(c_) * grid_.cell_volume(); }

double PoreLiquid::volume_in_bodies(const std::vector<double>& alpha) const {
  std::vector<double> over(c_.size(), 0.0);
  for (std::size_t i = 0; i < c_.size(); ++i) over[i] = std::max(c_[i] - fluid_part(alpha[i]), 0.0);
  return grid_.sum_owned(over) * grid_.cell_volume();
}

}  // namespace tessera
