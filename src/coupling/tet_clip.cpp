// SPDX-License-Identifier: MIT
#include "coupling/tet_clip.hpp"

#include <cmath>

namespace tessera {
namespace {

// The point of edge (a, b) where the signed distance s (sa at a, sb at b, opposite signs) is zero.
// Interpolated from the vertex on the kept side, the same expression whichever side asks: the two
// pieces of a cut share the point's bits.
inline Vec3 cut_point(const Vec3& a, double sa, const Vec3& b, double sb) {
  const bool swap = sa > sb;  // canonical direction: from the lower signed distance
  const Vec3& p = swap ? b : a;
  const Vec3& q = swap ? a : b;
  const double sp = swap ? sb : sa, sq = swap ? sa : sb;
  const double t = sp / (sp - sq);
  return p + (q - p) * t;
}

// Prism with triangle (a0, a1, a2) and opposite triangle (b0, b1, b2), ai joined to bi by an edge,
// sides planar: three tetrahedra.
inline void push_prism(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                       const Vec3& b2, std::vector<Tet>& out) {
  out.push_back({a0, a1, a2, b0});
  out.push_back({a1, a2, b0, b1});
  out.push_back({a2, b0, b1, b2});
}

}  // namespace

double tet_volume(const Tet& t) {
  const Vec3 a = t[1] - t[0], b = t[2] - t[0], c = t[3] - t[0];
  return std::abs(dot(a, cross(b, c))) / 6.0;
}

void clip_tets(const std::vector<Tet>& in, int axis, double value, bool below, std::vector<Tet>& out) {
  for (const Tet& t : in) {
    // s <= 0: kept side.
    double s[4];
    int kept[4], dropped[4], nk = 0, nd = 0;
    for (int v = 0; v < 4; ++v) {
      s[v] = below ? t[v][axis] - value : value - t[v][axis];
      if (s[v] <= 0)
        kept[nk++] = v;
      else
        dropped[nd++] = v;
    }
    if (nk == 4) {
      out.push_back(t);
      continue;
    }
    // A kept vertex exactly on the plane (s = 0) with all others dropped: no volume.
    bool any_inside = false;
    for (int n = 0; n < nk; ++n) any_inside |= s[kept[n]] < 0;
    if (!any_inside) continue;
    auto cut = [&](int k, int d) { return cut_point(t[k], s[k], t[d], s[d]); };
    if (nk == 1) {
      const int a = kept[0];
      out.push_back({t[a], cut(a, dropped[0]), cut(a, dropped[1]), cut(a, dropped[2])});
    } else if (nk == 2) {
      const int a = kept[0], b = kept[1], c = dropped[0], d = dropped[1];
      // Wedge: triangle (a, ac, ad) joined to (b, bc, bd).
      push_prism(t[a], cut(a, c), cut(a, d), t[b], cut(b, c), cut(b, d), out);
    } else {  // nk == 3
      const int a = kept[0], b = kept[1], c = kept[2], d = dropped[0];
      // The tetrahedron less its corner at d: triangle (a, b, c) joined to (da, db, dc).
      push_prism(t[a], t[b], t[c], cut(a, d), cut(b, d), cut(c, d), out);
    }
  }
}

double tet_box_volume(const Tet& t, const Vec3& lo, const Vec3& hi) {
  std::vector<Tet> a{t}, b;
  for (int d = 0; d < 3; ++d) {
    b.clear();
    clip_tets(a, d, lo[d], false, b);
    a.clear();
    clip_tets(b, d, hi[d], true, a);
  }
  double v = 0;
  for (const Tet& p : a) v += tet_volume(p);
  return v;
}

}  // namespace tessera
