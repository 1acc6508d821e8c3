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
    cuts.push_back(at);
  }
  fit_slabs(cuts, lo, hi, min_width, spacing);
  return cuts;
}

void fit_slabs(std::vector<double>& cuts, double lo, double hi, double min_width, double spacing) {
  const int parts = static_cast<int>(cuts.size()) + 1;
  if (spacing > 0)
    for (double& at : cuts) at = lo + std::round((at - lo) / spacing) * spacing;
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

std::vector<double> cell_block_cuts(double lo, double hi, int cells, int parts) {
  std::vector<double> cuts;
  if (parts < 2 || cells < parts) return cuts;
  // The largest block equal slabs give (their cells by centre), and the 2^k units that reach it.
  const int largest = (cells + parts - 1) / parts;
  int unit = 1;
  for (int u = 2; cells % u == 0; u *= 2) {
    const int units = cells / u, most = (units + parts - 1) / parts * u, least = units / parts * u;
    if (most > largest || 10 * least < 9 * cells / parts) break;
    unit = u;
  }
  const int units = cells / unit;
  const double h = (hi - lo) / cells;
  for (int i = 1; i < parts; ++i) cuts.push_back(lo + static_cast<double>(i * units / parts * unit) * h);
  return cuts;
}

std::vector<double> flow_default_cuts(double lo, double hi, int cells, int parts) {
  std::vector<double> cuts = cell_block_cuts(lo, hi, cells, parts);
  if (static_cast<int>(cuts.size()) == parts - 1) return cuts;
  cuts.clear();
  for (int i = 1; i < parts; ++i) cuts.push_back(lo + (hi - lo) * static_cast<double>(i) / parts);
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

std::vector<double> rank_work(MPI_Comm comm, const StageWork& stage, const Vec3& lo, const Vec3& hi,
                              std::array<int, 3> dims, const CutPlanes& interior) {
  std::vector<double> per_rank = rank_work(stage.samples, dims, interior);
  for (const WorkBox& box : stage.boxes) {
    // The share of the box in each slab of each direction (a box's weight is spread evenly).
    std::array<std::vector<double>, 3> share;
    bool empty = false;
    for (int d = 0; d < 3; ++d) {
      const auto n = static_cast<std::size_t>(dims[d]);
      share[d].assign(n, 0.0);
      const double a = std::clamp(box.lo[d], lo[d], hi[d]), z = std::clamp(box.hi[d], lo[d], hi[d]);
      if (!(z > a)) {
        empty = true;
        break;
      }
      for (std::size_t i = 0; i < n; ++i) {
        const double s_lo = i == 0 ? lo[d] : interior[d][i - 1], s_hi = i + 1 == n ? hi[d] : interior[d][i];
        share[d][i] = std::max(0.0, std::min(z, s_hi) - std::max(a, s_lo)) / (z - a);
      }
    }
    if (empty) continue;
    std::size_t r = 0;
    for (int k = 0; k < dims[2]; ++k)
      for (int j = 0; j < dims[1]; ++j)
        for (int i = 0; i < dims[0]; ++i, ++r)
          per_rank[r] += box.weight * share[0][static_cast<std::size_t>(i)] * share[1][static_cast<std::size_t>(j)] *
                         share[2][static_cast<std::size_t>(k)];
  }
  MPI_Allreduce(MPI_IN_PLACE, per_rank.data(), static_cast<int>(per_rank.size()), MPI_DOUBLE, MPI_SUM, comm);
  return per_rank;
}

double staged_imbalance(const std::vector<std::vector<double>>& per_stage) {
  double most = 0, mean = 0;
  for (const auto& w : per_stage) {
    if (w.empty()) continue;
    double sum = 0, top = 0;
    for (const double x : w) sum += x, top = std::max(top, x);
    most += top, mean += sum / static_cast<double>(w.size());
  }
  return mean > 0 ? most / mean : 1;
}

double staged_imbalance(MPI_Comm comm, const std::vector<double>& local_stage_work) {
  std::vector<double> most(local_stage_work), sum(local_stage_work);
  MPI_Allreduce(MPI_IN_PLACE, most.data(), static_cast<int>(most.size()), MPI_DOUBLE, MPI_MAX, comm);
  MPI_Allreduce(MPI_IN_PLACE, sum.data(), static_cast<int>(sum.size()), MPI_DOUBLE, MPI_SUM, comm);
  int size = 1;
  MPI_Comm_size(comm, &size);
  double top = 0, mean = 0;
  for (std::size_t s = 0; s < most.size(); ++s) top += most[s], mean += sum[s] / size;
  return mean > 0 ? top / mean : 1;
}

StagedCuts staged_cuts(MPI_Comm comm, const std::vector<StageWork>& stages, const Vec3& lo, const Vec3& hi,
                       std::array<int, 3> dims, const Vec3& min_width, const Vec3& spacing, int bins,
                       const CutPlanes* current) {
  // The candidates: the cuts now (kept on a tie), those that balance all the stages' work together,
  // those that balance each stage alone and blends of the two (a quarter, a half, three quarters of
  // the way), each put on the spacing with its slabs at least min_width, and equal slabs.
  std::vector<std::pair<CutPlanes, std::string>> candidates;
  if (current) candidates.emplace_back(*current, "current");
  StageWork all;
  for (const StageWork& s : stages) {
    all.samples.insert(all.samples.end(), s.samples.begin(), s.samples.end());
    all.boxes.insert(all.boxes.end(), s.boxes.begin(), s.boxes.end());
  }
  const CutPlanes summed = balanced_cuts(comm, all.samples, lo, hi, dims, min_width, spacing, bins, all.boxes);
  candidates.emplace_back(summed, "summed");
  for (std::size_t k = 0; k < stages.size(); ++k) {
    const CutPlanes own = balanced_cuts(comm, stages[k].samples, lo, hi, dims, min_width, spacing, bins, stages[k].boxes);
    for (const double t : {0.25, 0.5, 0.75, 1.0}) {
      CutPlanes blend = summed;
      for (int d = 0; d < 3; ++d) {
        for (std::size_t c = 0; c < blend[d].size(); ++c) blend[d][c] = (1 - t) * blend[d][c] + t * own[d][c];
        fit_slabs(blend[d], lo[d], hi[d], min_width[d], spacing[d]);
      }
      candidates.emplace_back(blend, "stage " + std::to_string(k) + (t < 1 ? " at " + std::to_string(t).substr(0, 4) : ""));
    }
  }
  CutPlanes blocks = equal_cuts(lo, hi, dims);
  bool on_cells = false;
  for (int d = 0; d < 3; ++d)  // on cells: in blocks the multigrid halves evenly (cell_block_cuts)
    if (spacing[d] > 0 && dims[d] > 1) {
      auto c = cell_block_cuts(lo[d], hi[d], static_cast<int>(std::lround((hi[d] - lo[d]) / spacing[d])), dims[d]);
      if (c.size() == blocks[d].size()) blocks[d] = std::move(c), on_cells = true;
    }
  if (on_cells) candidates.emplace_back(blocks, "cell blocks");
  candidates.emplace_back(equal_cuts(lo, hi, dims), "equal");
  StagedCuts best;
  best.imbalance = HUGE_VAL;
  for (const auto& [cuts, name] : candidates) {
    std::vector<std::vector<double>> per_stage;
    for (const StageWork& s : stages) per_stage.push_back(rank_work(comm, s, lo, hi, dims, cuts));
    const double cost = staged_imbalance(per_stage);
    if (cost < best.imbalance) best = {cuts, cost, name};  // the first of equals
  }
  return best;
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
