// SPDX-License-Identifier: MIT
// The bunker-shot seed's club head (section 3.1, eqs. 6-7; issue 5): a sand wedge in the plane of
// the swing, x forward (the direction of travel at the bottom of the swing), z up, the leading edge
// at the origin, club vertical (theta = 0).
//
//  - the face: a straight segment of length `face_length` from the leading edge L, leaning back
//    from the vertical by the loft angle, to the face's top F;
//  - the sole: the cubic Bezier curve P(t) = sum_i X_i(t) Q_i, X = ((1-t)^3, 3(1-t)^2 t,
//    3(1-t) t^2, t^3) (eqs. 6-7), from L (Q0) to the trailing edge T (Q3), sampled at
//    t = 0, 0.2, ..., 1 and joined by straight segments as in the seed. The seed's bounce is the
//    angle of the sole to the horizontal with the club vertical: here the chord L-T, of length
//    `sole_width`, goes back and down at the bounce angle, so the sole hangs below the leading
//    edge; Q1 and Q2 sit at a third and two thirds of the chord, pushed below it so that the curve
//    bulges `sole_camber` below the chord at t = 1/2 (the rounded sole of a wedge);
//  - the back: the straight segment T-F.
// The seed gives no control points: the chord, a 20 mm sole and a 1 mm camber are this model's
// choices (typical of sand wedges; cases/bunker_shot/README.md will give the reasons).
#pragma once
#include <array>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

struct ClubHeadDesign {
  double face_length = 0.065;  // m (seed)
  double loft_deg = 58;        // design variable (Table 2: 56, 58, 60, 65)
  double bounce_deg = 10;      // design variable (Table 2: 7, 10, 13)
  double sole_width = 0.020;   // m, chord from the leading to the trailing edge (chosen)
  double sole_camber = 0.001;  // m, the sole's bulge below its chord (chosen)
  int sole_segments = 5;       // t steps of 0.2 (seed)
};

// (x, z) points of the cubic Bezier sole at parameter t, and its tangent dP/dt.
std::array<double, 2> club_sole_point(const ClubHeadDesign& d, double t);
std::array<double, 2> club_sole_tangent(const ClubHeadDesign& d, double t);

// The outline, counter-clockwise in (x, z): L, F, T, then the sole's inner samples from T back to L
// (L is not repeated).
std::vector<std::array<double, 2>> club_head_outline(const ClubHeadDesign& d);

// The outline's side surface extruded along y over [y0 - width/2, y0 + width/2]: two triangles per
// outline edge, normals pointing out of the head. (A disc in the plane y = y0 only meets the side
// surface, so the end caps are left out.)
void extrude_outline(const std::vector<std::array<double, 2>>& outline, double y0, double width,
                     std::vector<Vec3>& nodes, std::vector<std::array<int, 3>>& triangles);

}  // namespace tessera
