// SPDX-License-Identifier: MIT
// The volume a tetrahedron shares with axis-aligned boxes, exactly (theory C1): the solid fraction
// of a grid cell is the sum, over the tetrahedra of the bodies, of these volumes over the cell's.
//
// Two ways, both exact up to round-off. clip_tets: clipping a tetrahedron by a plane leaves a
// tetrahedron (one vertex kept), a wedge (two kept) or a tetrahedron less a corner (three kept);
// each of the last two is a triangular prism with planar sides, cut into three tetrahedra: simple,
// the reference of the tests, but pieces multiply by up to 3 per plane. The rasterizer clips convex
// polytopes instead (one piece per cut, 8 to 10 times faster on the grains' fan meshes): a
// tetrahedron is cut into the slabs between grid planes along x, each piece along y, then z; the
// pieces of one cell sum to the shared volume, and the pieces of all cells to the tetrahedron's.
// A body whose surface bounds a convex polytope (ShapeTemplate::convex) is swept whole, as that one
// polytope: one piece per cell instead of one per tetrahedron and cell (theory C1).
#pragma once
#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstdint>
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
// only the cells with begin <= index < end are visited. Along a direction closed by walls, `first`
// and `last` are the grid's first and last cells, and they reach beyond the walls: a body pressed
// into a wall (its contact's overlap) keeps the volume beyond it in the wall's cells (theory C1).
struct CellRange {
  Vec3 lo;
  std::array<double, 3> h{};
  std::array<int, 3> begin{}, end{};
  std::array<int, 3> first{INT_MIN, INT_MIN, INT_MIN}, last{INT_MAX, INT_MAX, INT_MAX};
};

// A convex polytope as its faces, each a planar convex polygon (vertices in order around it).
struct Polytope {
  std::vector<Vec3> points;      // the faces' vertices, face after face
  std::vector<std::uint32_t> start{0};  // face k: points[start[k], start[k + 1])
  void clear() {
    points.clear();
    start.assign(1, 0);
  }
  std::size_t faces() const { return start.size() - 1; }
  void close_face() { start.push_back(static_cast<std::uint32_t>(points.size())); }
  void set_tet(const Tet& t);
  // One face per triangle (node indices into `nodes`), e.g. a convex body's surface.
  void set_triangles(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 3>>& triangles);
};

// Splits `in` by the plane x_axis = value into its parts below and above (either may come out
// empty). Each part is one convex polytope: the cut face is built from the points where the faces
// cross the plane, ordered by angle about their mean. Cut points come from the two end points of
// the crossed edge in a canonical order, so the parts share them bit for bit.
void split_polytope(const Polytope& in, int axis, double value, Polytope& below, Polytope& above,
                    std::vector<Vec3>& scratch);
// Volume: fans of its faces from the mean of its points (inside a convex polytope), summed.
double polytope_volume(const Polytope& p);

// Calls fn(i, j, k, volume) for every cell of `cells` that a tetrahedron, or a convex polytope,
// overlaps with a positive volume, each cell at most once. The solid is swept over the cells of its
// bounding box along x, each slab along y, then z: one polytope per piece (no pieces multiply). The
// sweep covers the whole bounding box whatever the range, and only cells in the range are reported:
// so a cell's volume has the same bits whichever range (rank) asks. Beyond `first` and `last` the box
// is cut back to them: the cells there take all of the solid on their side.
class CellRasterizer {
 public:
  template <class F>
  void overlaps(const Tet& t, const CellRange& cells, F&& fn) {
    std::array<int, 3> a{}, b{};
    if (!cell_box(t.data(), t.size(), cells, a, b)) return;
    if (a == b) {  // the common case when cells are larger than tetrahedra
      fn(a[0], a[1], a[2], tet_volume(t));
      return;
    }
    level_[0].set_tet(t);
    descend(0, a, b, cells, {0, 0, 0}, fn);
  }
  // p: a closed convex polytope (its faces planar convex polygons).
  template <class F>
  void overlaps(const Polytope& p, const CellRange& cells, F&& fn) {
    std::array<int, 3> a{}, b{};
    if (p.faces() < 4 || !cell_box(p.points.data(), p.points.size(), cells, a, b)) return;
    if (a == b) {
      fn(a[0], a[1], a[2], polytope_volume(p));
      return;
    }
    level_[0] = p;
    descend(0, a, b, cells, {0, 0, 0}, fn);
  }

 private:
  // The cells the points' bounding box touches, [a, b] per direction (clamped to first and last);
  // false when they miss the range.
  static bool cell_box(const Vec3* pts, std::size_t n, const CellRange& cells, std::array<int, 3>& a,
                       std::array<int, 3>& b) {
    for (int d = 0; d < 3; ++d) {
      double mn = pts[0][d], mx = pts[0][d];
      for (std::size_t v = 1; v < n; ++v) mn = std::min(mn, pts[v][d]), mx = std::max(mx, pts[v][d]);
      a[d] = std::clamp(int(std::floor((mn - cells.lo[d]) / cells.h[d])), cells.first[d], cells.last[d]);
      b[d] = std::clamp(int(std::floor((mx - cells.lo[d]) / cells.h[d])), cells.first[d], cells.last[d]);
      if (b[d] < cells.begin[d] || a[d] >= cells.end[d]) return false;
    }
    return true;
  }
  template <class F>
  void descend(int d, const std::array<int, 3>& a, const std::array<int, 3>& b, const CellRange& cells,
               std::array<int, 3> idx, F&& fn) {
    Polytope* rest = &level_[d];
    for (int i = a[d]; i <= b[d]; ++i) {
      idx[d] = i;
      Polytope* piece = &piece_[d];
      if (i < b[d]) {
        split_polytope(*rest, d, cells.lo[d] + (i + 1) * cells.h[d], *piece, spare_[d], scratch_);
        std::swap(*rest, spare_[d]);
      } else {
        std::swap(*piece, *rest);
      }
      const bool in_range = i >= cells.begin[d] && i < cells.end[d];
      if (!in_range || piece->faces() < 4) {
        if (i >= cells.end[d]) return;
        continue;
      }
      if (d < 2) {
        std::swap(level_[d + 1], *piece);
        descend(d + 1, a, b, cells, idx, fn);
      } else {
        const double v = polytope_volume(*piece);
        if (v > 0) fn(idx[0], idx[1], idx[2], v);
      }
    }
  }
  std::array<Polytope, 3> level_, piece_, spare_;
  std::vector<Vec3> scratch_;
};

}  // namespace tessera
