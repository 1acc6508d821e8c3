// SPDX-License-Identifier: MIT
// What a drop leaves in a bed of grains, seen from above (drop-impact seed, section 3.(1); theory
// D1-D6): the smoothed sand surface, the crater volume by the seed's formula (eq. 14) and by the
// experiments' two sections (eqs. 9-13), the bed's top near the impact axis and its porosity.
//
// A grain is represented by its horizontal centre and its top: the highest node of its tetrahedra
// (D1). The smoothing grid (spacing cell = the seed's Delta x*) has a cell centred on the impact
// axis; a cell's height h_s is the mean top of the grains whose centres lie in it and whose tops lie
// within `surface_layer` of the highest top there (D2: the seed averages "the grains in the
// smoothing cell" without saying how deep; a layer of one grain diameter keeps the surface grains,
// an infinite one averages the whole column). Rings of width dr about the axis average the cells
// whose centres they hold (D3); b is the first ring's height (r = dr/2), a and L the largest ring
// height and its radius, H = a - b and V = pi H (3 L^2 + H^2) / 6 (D4). The sections through the
// axis along x and y give the experiments' a_1, a_2, b, L_1 and L_2 (D5, eq. 13).
#pragma once
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

class DemSolver;

// A grain seen from above: its centre's horizontal position and its highest node.
struct GrainTop {
  double x = 0, y = 0, top = 0;
};

// Collective: the tops of every shaped body, on every rank, in body-id order (the same list on any
// rank count).
std::vector<GrainTop> grain_tops(const DemSolver& dem);

// Collective: the solid volume of the shaped bodies below the height z (their tetrahedra clipped
// exactly), summed exactly.
double solid_volume_below(const DemSolver& dem, double z);

// The highest top among the grains whose centres lie within `radius` of (cx, cy) horizontally (the
// seed's H_s); -infinity when there is none.
double bed_top(const std::vector<GrainTop>& tops, double cx, double cy, double radius);

struct CraterSettings {
  double cx = 0, cy = 0;       // the impact axis
  double cell = 0;             // smoothing grid spacing (Delta x*)
  double ring_width = 0;       // dr
  double surface_layer = 0;    // grains counted in a cell: top within this of the cell's highest
  double max_radius = 0;       // rings and sections end here
};

struct CraterSection {  // along one axis through the impact axis (D5)
  double a1 = 0, a2 = 0;  // rim heights, on the low and the high side
  double b = 0;           // height midway between the rims
  double length = 0;      // rim to rim (L_1 or L_2)
  double depth() const { return 0.5 * (a1 + a2) - b; }
};

struct Crater {
  // The smoothed surface: cells (i, j) for i, j in [-n, n], centre (cx + i cell, cy + j cell);
  // height[(j + n) (2 n + 1) + (i + n)], NaN where no grain's centre lies.
  int n = 0;
  std::vector<double> height;
  // Ring k spans k dr <= r < (k + 1) dr; its height is the mean of its cells' (NaN: none).
  std::vector<double> ring_radius, ring_height;
  std::vector<int> ring_cells;
  double a = 0, b = 0, rim_radius = 0, depth = 0, volume = 0;  // D4: a, b, L, H, V (eq. 14)
  CraterSection section_x, section_y;
  double section_volume = 0;  // eq. 13 with l^2 = L_1 L_2 and H the mean of the two sections'
  bool valid = false;          // false: too few rings or cells to find a rim
};

Crater measure_crater(const std::vector<GrainTop>& tops, const CraterSettings& s);

}  // namespace tessera
