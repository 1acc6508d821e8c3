// SPDX-License-Identifier: MIT
#include "core/decomposition.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "core/errors.hpp"

namespace tessera {

std::array<int, 3> Decomposition::choose_dims(int size, const Vec3& extent, std::array<int, 3> req) {
  std::array<int, 3> best{0, 0, 0};
  double best_surface = std::numeric_limits<double>::infinity();
  for (int a = 1; a <= size; ++a) {
    if (size % a || (req[0] && req[0] != a)) continue;
    for (int b = 1; b <= size / a; ++b) {
      if ((size / a) % b || (req[1] && req[1] != b)) continue;
      const int c = size / a / b;
      if (req[2] && req[2] != c) continue;
      const double lx = extent.x / a, ly = extent.y / b, lz = extent.z / c;
      const double surface = lx * ly + ly * lz + lz * lx;
      // Ties go to the earlier (x-major) split so the choice is reproducible.
      if (surface < best_surface * (1 - 1e-12)) best_surface = surface, best = {a, b, c};
    }
  }
  if (best[0] == 0)
    throw InputError("domain.process_grid", "", "a grid whose product is the rank count " + std::to_string(size));
  return best;
}

Decomposition::Decomposition(MPI_Comm comm, const Vec3& lo, const Vec3& hi, std::array<int, 3> requested,
                             const Cuts& interior)
    : global_lo_(lo), global_hi_(hi) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  // Given cuts fix the grid along their direction.
  for (int d = 0; d < 3; ++d) {
    if (interior[d].empty()) continue;
    const int n = static_cast<int>(interior[d].size()) + 1;
    if (requested[d] && requested[d] != n)
      throw InputError(std::string("domain.cuts.") + "xyz"[d], "",
                       std::to_string(n - 1) + " cuts make " + std::to_string(n) + " sub-domains along " + "xyz"[d] +
                           ", but domain.process_grid asks for " + std::to_string(requested[d]));
    requested[d] = n;
    for (std::size_t i = 0; i < interior[d].size(); ++i) {
      const double c = interior[d][i], before = i ? interior[d][i - 1] : lo[d];
      if (!(c > before) || !(c < hi[d]))
        throw InputError(std::string("domain.cuts.") + "xyz"[d], std::to_string(c),
                         "increasing cut planes strictly inside the box (" + std::to_string(lo[d]) + " to " +
                             std::to_string(hi[d]) + ")");
    }
  }
  dims_ = choose_dims(size, hi - lo, requested);
  const int periods[3] = {0, 0, 0};
  // reorder = 0: rank numbering must not depend on the MPI library's placement choices.
  MPI_Cart_create(comm, 3, dims_.data(), periods, 0, &cart_);
  MPI_Comm_rank(cart_, &rank_);
  MPI_Comm_size(cart_, &size_);
  MPI_Cart_coords(cart_, rank_, 3, coords_.data());
  for (int d = 0; d < 3; ++d) {
    MPI_Cart_shift(cart_, d, 1, &neighbors_[d][0], &neighbors_[d][1]);
    cuts_[d].resize(dims_[d] + 1);
    for (int i = 0; i <= dims_[d]; ++i)
      cuts_[d][i] = i == 0 ? lo[d]
                    : i == dims_[d] ? hi[d]
                    : interior[d].empty() ? lo[d] + (hi[d] - lo[d]) * static_cast<double>(i) / dims_[d]
                                          : interior[d][static_cast<std::size_t>(i - 1)];
  }
}

void Decomposition::set_cuts(const Cuts& interior) {
  for (int d = 0; d < 3; ++d) {
    const auto& c = interior[d];
    if (static_cast<int>(c.size()) != dims_[d] - 1)
      throw RunError("Decomposition::set_cuts: " + std::to_string(c.size()) + " cuts along axis " + std::to_string(d) +
                     " for " + std::to_string(dims_[d]) + " sub-domains");
    for (std::size_t i = 0; i < c.size(); ++i)
      if (!(c[i] > (i ? c[i - 1] : global_lo_[d])) || !(c[i] < global_hi_[d]))
        throw RunError("Decomposition::set_cuts: cuts along axis " + std::to_string(d) +
                       " must increase strictly inside the box");
  }
  for (int d = 0; d < 3; ++d)
    for (int i = 1; i < dims_[d]; ++i) cuts_[d][i] = interior[d][static_cast<std::size_t>(i - 1)];
}

Decomposition::Cuts Decomposition::interior_cuts() const {
  Cuts c;
  for (int d = 0; d < 3; ++d) c[d].assign(cuts_[d].begin() + 1, cuts_[d].end() - 1);
  return c;
}

Decomposition::~Decomposition() {
  if (cart_ != MPI_COMM_NULL) MPI_Comm_free(&cart_);
}

Vec3 Decomposition::sub_lo() const { return {cuts_[0][coords_[0]], cuts_[1][coords_[1]], cuts_[2][coords_[2]]}; }

Vec3 Decomposition::sub_hi() const {
  return {cuts_[0][coords_[0] + 1], cuts_[1][coords_[1] + 1], cuts_[2][coords_[2] + 1]};
}

int Decomposition::owner_coord(int d, double x) const {
  const auto& c = cuts_[d];
  // First cut strictly above x, minus one: cell c[i] <= x < c[i+1].
  const auto it = std::upper_bound(c.begin() + 1, c.end() - 1, x);
  return static_cast<int>(it - (c.begin() + 1));
}

bool Decomposition::owns(const Vec3& p) const {
  for (int d = 0; d < 3; ++d)
    if (owner_coord(d, p[d]) != coords_[d]) return false;
  return true;
}

int Decomposition::owner_rank(const Vec3& p) const {
  int c[3];
  for (int d = 0; d < 3; ++d) c[d] = owner_coord(d, p[d]);
  int r = 0;
  MPI_Cart_rank(cart_, c, &r);
  return r;
}

}  // namespace tessera
