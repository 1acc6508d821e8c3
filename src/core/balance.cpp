// SPDX-License-Identifier: MIT
#include "core/balance.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace tessera {

std::vector<double> balanced_cuts(const std::vector<double>& x, const std::vector<double>& weight, double lo,
                                  double hi, int parts, double min_width, double spacing) {
  if (parts < 1 || !(hi > lo)) throw std::invalid_argument("balanced_cuts: at least one part of a non-empty range");
  std::vector<double> cuts;
  if (parts == 1) return cuts;
  if (parts * min_width > hi - lo)
    throw std::invalid_argument("balanced_cuts: " + std::to_string(parts) + " slabs of at least " +
                                std::to_string(min_width) + " do not fit in " + std::to_string(hi - lo));
  // The marginal distribution: samples in position order, the cumulative weight.
  std::vector<std::size_t> order(x.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return x[a] < x[b]; });
  double total = 0;
  for (const double w : weight) total += w;
  // Cut c at the position where the cumulative weight reaches c / parts of the total, midway
  // between the two samples that straddle it (no samples: equal slabs).
  std::size_t k = 0;
  double below = 0;
  for (int c = 1; c < parts; ++c) {
    double at = lo + (hi - lo) * c / parts;
    if (total > 0) {
      const double target = total * c / parts;
      while (k < order.size() && below + weight[order[k]] <= target) below += weight[order[k++]];
      const double left = k == 0 ? lo : std::clamp(x[order[k - 1]], lo, hi);
      const double right = k < order.size() ? std::clamp(x[order[k]], lo, hi) : hi;
      at = 0.5 * (left + right);
    }
    if (spacing > 0) at = lo + std::round((at - lo) / spacing) * spacing;
    cuts.push_back(at);
  }
  // Widths: every slab at least min_width (and one spacing), pushing cuts up, then down from hi.
  const double w = std::max(min_width, spacing);
  for (int c = 0; c < parts - 1; ++c) {
    const double prev = c == 0 ? lo : cuts[c - 1];
    if (cuts[c] < prev + w) cuts[c] = spacing > 0 ? prev + std::ceil(w / spacing - 1e-9) * spacing : prev + w;
  }
  for (int c = parts - 2; c >= 0; --c) {
    const double next = c == parts - 2 ? hi : cuts[c + 1];
    if (cuts[c] > next - w) cuts[c] = spacing > 0 ? next - std::ceil(w / spacing - 1e-9) * spacing : next - w;
  }
  return cuts;
}

CutPlanes balanced_cuts(const std::vector<WorkSample>& work, const Vec3& lo, const Vec3& hi, std::array<int, 3> dims,
                        const Vec3& min_width, const Vec3& spacing) {
  CutPlanes cuts;
  std::vector<double> x(work.size()), w(work.size());
  for (std::size_t i = 0; i < work.size(); ++i) w[i] = work[i].weight;
  for (int d = 0; d < 3; ++d) {
    for (std::size_t i = 0; i < work.size(); ++i) x[i] = work[i].x[d];
    cuts[d] = balanced_cuts(x, w, lo[d], hi[d], dims[d], min_width[d], spacing[d]);
  }
  return cuts;
}

CutPlanes equal_cuts(const Vec3& lo, const Vec3& hi, std::array<int, 3> dims) {
  CutPlanes cuts;
  for (int d = 0; d < 3; ++d)
    for (int c = 1; c < dims[d]; ++c) cuts[d].push_back(lo[d] + (hi[d] - lo[d]) * c / dims[d]);
  return cuts;
}

int grid_cell(const Vec3& x, std::array<int, 3> dims, const CutPlanes& interior) {
  int r = 0, stride = 1;
  for (int d = 0; d < 3; ++d) {
    const auto& c = interior[static_cast<std::size_t>(d)];
    r += static_cast<int>(std::upper_bound(c.begin(), c.end(), x[d]) - c.begin()) * stride;
    stride *= dims[static_cast<std::size_t>(d)];
  }
  return r;
}

std::vector<double> rank_work(const std::vector<WorkSample>& work, std::array<int, 3> dims,
                              const CutPlanes& interior) {
  std::vector<double> per_rank(static_cast<std::size_t>(dims[0]) * dims[1] * dims[2], 0.0);
  for (const auto& s : work) per_rank[static_cast<std::size_t>(grid_cell(s.x, dims, interior))] += s.weight;
  return per_rank;
}

double imbalance(const std::vector<double>& per_rank) {
  if (per_rank.empty()) return 1;
  double sum = 0, most = 0;
  for (const double w : per_rank) sum += w, most = std::max(most, w);
  return sum > 0 ? most * static_cast<double>(per_rank.size()) / sum : 1;
}

CutPlanes balanced_cuts(MPI_Comm comm, const std::vector<WorkSample>& local, const Vec3& lo, const Vec3& hi,
                        std::array<int, 3> dims, const Vec3& min_width, const Vec3& spacing, int bins,
                        const std::vector<WorkBox>& boxes) {
  CutPlanes cuts;
  std::vector<double> hist(static_cast<std::size_t>(bins)), x(hist.size());
  for (int d = 0; d < 3; ++d) {
    if (dims[d] == 1) continue;
    std::fill(hist.begin(), hist.end(), 0.0);
    const double width = (hi[d] - lo[d]) / bins;
    for (const auto& s : local) {
      const int b = std::clamp(static_cast<int>((s.x[d] - lo[d]) / width), 0, bins - 1);
      hist[static_cast<std::size_t>(b)] += s.weight;
    }
    for (const auto& box : boxes) {
      const double a = std::clamp(box.lo[d], lo[d], hi[d]), z = std::clamp(box.hi[d], lo[d], hi[d]);
      if (!(z > a)) continue;
      const double per_length = box.weight / (z - a);
      const int first = std::clamp(static_cast<int>((a - lo[d]) / width), 0, bins - 1);
      const int last = std::clamp(static_cast<int>((z - lo[d]) / width), 0, bins - 1);
      for (int b = first; b <= last; ++b) {
        const double b_lo = lo[d] + b * width, b_hi = b_lo + width;
        const double covered = std::min(z, b_hi) - std::max(a, b_lo);
        if (covered > 0) hist[static_cast<std::size_t>(b)] += per_length * covered;
      }
    }
    MPI_Allreduce(MPI_IN_PLACE, hist.data(), bins, MPI_DOUBLE, MPI_SUM, comm);
    for (int b = 0; b < bins; ++b) x[static_cast<std::size_t>(b)] = lo[d] + (b + 0.5) * width;
    cuts[d] = balanced_cuts(x, hist, lo[d], hi[d], dims[d], min_width[d], spacing[d]);
  }
  return cuts;
}

double imbalance(MPI_Comm comm, double local_work) {
  double most = local_work, sum = local_work;
  int size = 1;
  MPI_Comm_size(comm, &size);
  MPI_Allreduce(MPI_IN_PLACE, &most, 1, MPI_DOUBLE, MPI_MAX, comm);
  MPI_Allreduce(MPI_IN_PLACE, &sum, 1, MPI_DOUBLE, MPI_SUM, comm);
  return sum > 0 ? most * size / sum : 1;
}

}  // namespace tessera
