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

void Polytope::set_triangles(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 3>>& triangles) {
  clear();
  points.reserve(3 * triangles.size());
  start.reserve(triangles.size() + 1);
  for (const auto& tri : triangles) {
    for (int v : tri) points.push_back(nodes[static_cast<std::size_t>(v)]);
    close_face();
  }
}

void Polytope::set_tet(const Tet& t) {
  clear();
  const int f[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  for (const auto& face : f) {
    for (int v : face) points.push_back(t[v]);
    close_face();
  }
}

void split_polytope(const Polytope& in, int axis, double value, Polytope& below, Polytope& above,
                    std::vector<Vec3>& cut) {
  below.clear();
  above.clear();
  cut.clear();
  for (std::size_t f = 0; f < in.faces(); ++f) {
    const std::uint32_t first = in.start[f], end = in.start[f + 1], m = end - first;
    const Vec3* v = &in.points[first];
    double s_min = 1e300, s_max = -1e300;
    for (std::uint32_t i = 0; i < m; ++i) {
      const double s = v[i][axis] - value;
      s_min = std::min(s_min, s), s_max = std::max(s_max, s);
      if (s == 0) cut.push_back(v[i]);
    }
    if (s_min == 0 && s_max == 0) continue;  // in the plane: the cut face will be it
    if (s_max <= 0 || s_min >= 0) {  // the face on one side
      if (s_max <= 0) {
        below.points.insert(below.points.end(), v, v + m);
        below.close_face();
      }
      if (s_min >= 0) {
        above.points.insert(above.points.end(), v, v + m);
        above.close_face();
      }
      continue;
    }
    const std::size_t b0 = below.points.size(), a0 = above.points.size();
    for (std::uint32_t i = 0; i < m; ++i) {
      const Vec3& p = v[i];
      const Vec3& q = v[(i + 1) % m];
      const double sp = p[axis] - value, sq = q[axis] - value;
      if (sp <= 0) below.points.push_back(p);
      if (sp >= 0) above.points.push_back(p);
      if ((sp < 0 && sq > 0) || (sp > 0 && sq < 0)) {
        const Vec3 c = cut_point(p, sp, q, sq);
        below.points.push_back(c);
        above.points.push_back(c);
        cut.push_back(c);
      }
    }
    if (below.points.size() - b0 >= 3)
      below.close_face();
    else
      below.points.resize(b0);
    if (above.points.size() - a0 >= 3)
      above.close_face();
    else
      above.points.resize(a0);
  }
  if (cut.size() < 3) return;
  // The cut face: its points by angle about their mean, in the plane's two other axes; each point
  // appears once per face through it, with the same bits: duplicates fall next to each other.
  const int u = (axis + 1) % 3, w = (axis + 2) % 3;
  double cu = 0, cw = 0;
  for (const Vec3& p : cut) cu += p[u], cw += p[w];
  cu /= double(cut.size()), cw /= double(cut.size());
  // Pseudo-angle (monotone in the angle, no trigonometry), computed once per point; insertion
  // sort (a handful of points).
  thread_local std::vector<std::pair<double, Vec3>> keyed;
  keyed.clear();
  for (const Vec3& p : cut) {
    const double du = p[u] - cu, dw = p[w] - cw, l1 = std::abs(du) + std::abs(dw);
    double key = l1 > 0 ? dw / l1 : 0;  // in [-1, 1] on the right half
    if (du < 0) key = 2 - key;          // (1, 3) on the left half
    else if (key < 0) key += 4;         // the lower right quadrant after the left half
    keyed.emplace_back(key, p);
  }
  for (std::size_t i = 1; i < keyed.size(); ++i)
    for (std::size_t j = i; j > 0; --j) {
      const auto& x = keyed[j - 1];
      const auto& y = keyed[j];
      const bool after = x.first > y.first ||
                         (x.first == y.first && (x.second[u] > y.second[u] ||
                                                 (x.second[u] == y.second[u] && x.second[w] > y.second[w])));
      if (!after) break;
      std::swap(keyed[j - 1], keyed[j]);
    }
  for (std::size_t i = 0; i < keyed.size(); ++i) cut[i] = keyed[i].second;
  auto same = [&](const Vec3& p, const Vec3& q) { return p[u] == q[u] && p[w] == q[w]; };
  cut.erase(std::unique(cut.begin(), cut.end(), same), cut.end());
  while (cut.size() > 1 && same(cut.front(), cut.back())) cut.pop_back();
  if (cut.size() < 3) return;
  for (Polytope* side : {&below, &above}) {
    if (side->faces() == 0) continue;
    side->points.insert(side->points.end(), cut.begin(), cut.end());
    side->close_face();
  }
}

double polytope_volume(const Polytope& p) {
  if (p.faces() < 4) return 0;
  Vec3 o;
  for (const Vec3& q : p.points) o += q;
  o = o / double(p.points.size());
  double v = 0;
  for (std::size_t f = 0; f < p.faces(); ++f) {
    const Vec3* q = &p.points[p.start[f]];
    const std::uint32_t m = p.start[f + 1] - p.start[f];
    const Vec3 a = q[0] - o;
    for (std::uint32_t j = 1; j + 1 < m; ++j) v += std::abs(dot(a, cross(q[j] - o, q[j + 1] - o)));
  }
  return v / 6.0;
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
