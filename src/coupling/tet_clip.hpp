// SPDX-License-Identifier: MIT
// The volume a tetrahedron shares with axis-aligned boxes, exactly (theory C1): the solid fraction
// of a grid cell is the sum, over the tetrahedra of the bodies, of these volumes over the cell's.
//
// Clipping a tetrahedron by a plane leaves a tetrahedron (one vertex kept), a wedge (two kept) or
// a tetrahedron less a corner (three kept); each of the last two is a triangular prism with planar
// sides and is cut into three tetrahedra. So a tetrahedron clipped by any number of planes is a list
// of tetrahedra, and volumes add. A tetrahedron is laid over a grid by cutting it into the slabs
// between grid planes along x, then each piece along y, then z: the pieces of one cell sum to the
// exact shared volume up to round-off, and the pieces of all cells to the tetrahedron's volume.
#pragma once
#include <array>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

using Tet = std::array<Vec3, 4>;

// Unsigned volume of a tetrahedron.
double tet_volume(const Tet& t);

// Appends to `out` the pieces of each tetrahedron of `in` where x_axis <= value (below = true) or
// x_axis >= value (below = false). Pieces of zero volume are dropped.
void clip_tets(const std::vector<Tet>& in, int axis, double value, bool below, std::vector<Tet>& out);

// Volume of the tetrahedron inside the box [lo, hi].
double tet_box_volume(const Tet& t, const Vec3& lo, const Vec3& hi);

// A uniform grid of cells: cell (i, j, k) spans lo + (i, j, k) h to lo + (i + 1, j + 1, k + 1) h;
// only the cells with begin <= index < end are visited.
struct CellRange {
  Vec3 lo;
  std::array<double, 3> h{};
  std::array<int, 3> begin{}, end{};
};

// Calls fn(i, j, k, volume) for every cell of `cells` that the tetrahedron overlaps with a positive
// volume, in no particular order, each cell at most once. `scratch` holds the pieces (reused between
// calls to avoid allocation).
class TetRasterizer {
 public:
  template <class F>
  void overlaps(const Tet& t, const CellRange& cells, F&& fn) {
    std::array<int, 3> a{}, b{};  // index range [a, b] the bounding box touches, within the range
    for (int d = 0; d < 3; ++d) {
      double mn = t[0][d], mx = t[0][d];
      for (int v = 1; v < 4; ++v) mn = std::min(mn, t[v][d]), mx = std::max(mx, t[v][d]);
      a[d] = std::max(cells.begin[d], int(std::floor((mn - cells.lo[d]) / cells.h[d])));
      b[d] = std::min(cells.end[d] - 1, int(std::floor((mx - cells.lo[d]) / cells.h[d])));
      if (a[d] > b[d]) return;
    }
    const bool whole = a == b && inside(t, cells, a);
    if (whole) {  // the common case when cells are larger than tetrahedra
      fn(a[0], a[1], a[2], tet_volume(t));
      return;
    }
    slabs_[0].assign(1, t);
    descend(0, a, b, cells, {0, 0, 0}, fn);
  }

 private:
  static bool inside(const Tet& t, const CellRange& c, const std::array<int, 3>& idx) {
    for (int d = 0; d < 3; ++d) {
      const double lo = c.lo[d] + idx[d] * c.h[d], hi = c.lo[d] + (idx[d] + 1) * c.h[d];
      for (int v = 0; v < 4; ++v)
        if (t[v][d] < lo || t[v][d] > hi) return false;
    }
    return true;
  }
  // Cuts slabs_[d] along direction d into the cells a[d]..b[d]; recurses into d + 1.
  template <class F>
  void descend(int d, const std::array<int, 3>& a, const std::array<int, 3>& b, const CellRange& cells,
               std::array<int, 3> idx, F&& fn) {
    std::vector<Tet>& rest = slabs_[d];
    for (int i = a[d]; i <= b[d] && !rest.empty(); ++i) {
      idx[d] = i;
      std::vector<Tet>& piece = d == 2 ? leaf_ : slabs_[d + 1];
      piece.clear();
      const double lo_plane = cells.lo[d] + i * cells.h[d], hi_plane = cells.lo[d] + (i + 1) * cells.h[d];
      // The part below the cell's high plane is this cell's (its part below the low plane was cut
      // off by the previous cell, or lies outside the visited range when i == a[d]).
      if (i == a[d]) {
        above_.clear();
        clip_tets(rest, d, lo_plane, false, above_);
        rest.swap(above_);
      }
      if (i < b[d]) {
        clip_tets(rest, d, hi_plane, true, piece);
        above_.clear();
        clip_tets(rest, d, hi_plane, false, above_);
        rest.swap(above_);
      } else {
        above_.clear();
        clip_tets(rest, d, hi_plane, true, above_);
        piece.swap(above_);
        rest.clear();
      }
      if (piece.empty()) continue;
      if (d < 2) {
        // The next direction works on its own copy: slabs_[d + 1] is `piece`.
        descend(d + 1, a, b, cells, idx, fn);
      } else {
        double v = 0;
        for (const Tet& p : piece) v += tet_volume(p);
        if (v > 0) fn(idx[0], idx[1], idx[2], v);
      }
    }
  }
  std::array<std::vector<Tet>, 3> slabs_;
  std::vector<Tet> leaf_, above_;
};

}  // namespace tessera
