// SPDX-License-Identifier: MIT
#include "solid/club_head.hpp"

#include <cmath>
#include <numbers>

namespace tessera {
namespace {

struct Controls {
  std::array<double, 2> q[4];
};

Controls controls(const ClubHeadDesign& d) {
  const double b = d.bounce_deg * std::numbers::pi / 180, w = d.sole_width, c = 4.0 / 3.0 * d.sole_camber;
  const double ex = -std::cos(b), ez = -std::sin(b);  // along the chord, back and down
  const double nx = std::sin(b), nz = -std::cos(b);   // across it, downward
  return {{{0, 0},
           {w / 3 * ex + c * nx, w / 3 * ez + c * nz},
           {2 * w / 3 * ex + c * nx, 2 * w / 3 * ez + c * nz},
           {w * ex, w * ez}}};
}

}  // namespace

std::array<double, 2> club_sole_point(const ClubHeadDesign& d, double t) {
  const Controls c = controls(d);
  const double s = 1 - t, w[4] = {s * s * s, 3 * s * s * t, 3 * s * t * t, t * t * t};  // eq. 7
  std::array<double, 2> p{0, 0};
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 2; ++k) p[k] += w[i] * c.q[i][k];  // eq. 6
  return p;
}

std::array<double, 2> club_sole_tangent(const ClubHeadDesign& d, double t) {
  const Controls c = controls(d);
  const double s = 1 - t, w[3] = {3 * s * s, 6 * s * t, 3 * t * t};
  std::array<double, 2> p{0, 0};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 2; ++k) p[k] += w[i] * (c.q[i + 1][k] - c.q[i][k]);
  return p;
}

std::vector<std::array<double, 2>> club_head_outline(const ClubHeadDesign& d) {
  const double loft = d.loft_deg * std::numbers::pi / 180;
  std::vector<std::array<double, 2>> out;
  out.push_back({0, 0});                                                                                      // L
  out.push_back({-d.face_length * std::sin(loft), d.face_length * std::cos(loft)});                           // F
  for (int i = d.sole_segments; i >= 1; --i) out.push_back(club_sole_point(d, double(i) / d.sole_segments));  // T ...
  return out;
}

void extrude_outline(const std::vector<std::array<double, 2>>& outline, double y0, double width,
                     std::vector<Vec3>& nodes, std::vector<std::array<int, 3>>& triangles) {
  nodes.clear();
  triangles.clear();
  const int n = int(outline.size());
  for (const auto& p : outline) {
    nodes.push_back({p[0], y0 - 0.5 * width, p[1]});
    nodes.push_back({p[0], y0 + 0.5 * width, p[1]});
  }
  // Edge P0 -> P1 of a counter-clockwise outline: A, B at y-, D, C at y+; (A, D, B) and (B, D, C)
  // have the outward normal (dz, 0, -dx).
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    const int A = 2 * i, D = 2 * i + 1, B = 2 * j, C = 2 * j + 1;
    triangles.push_back({A, D, B});
    triangles.push_back({B, D, C});
  }
}

}  // namespace tessera
