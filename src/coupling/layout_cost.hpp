// SPDX-License-Identifier: MIT
// What the solid fraction's lay-out costs each rank of a decomposition, done here on one core: the
// scaling model's price of the coupled step's body stages (tools/scaling.py; `tessera balance`).
//
// Each rank lays out, over its owned cells, its owned bodies and the ghosts whose farthest
// tetrahedron node reaches its cells (SolidPhase::update's rule, theory C1). A ghost that reaches
// a rank's cells with a sliver costs that rank less than a whole body, but more than its share of
// cells: the rasterizer sweeps the body's whole bounding box up to the rank's last cell (so a cell's
// volume has the same bits on any rank). So the lay-out is timed, rank by rank, rather than counted:
// each rank's bodies laid out `repeats` times, each rank's least time kept (a host's interruptions
// only add). Also counted exactly: the cells each rank's lay-outs report (the fluid force's and
// the sums' work: each body's cells, once each, whichever rank owns them).
#pragma once
#include <array>
#include <vector>

#include "core/vec3.hpp"
#include "solid/rigid_rotation.hpp"
#include "solid/shape.hpp"

namespace tessera {

struct BodyPose {
  Vec3 x;
  Quaternion q;
  int shape = 0;  // 1-based into the shapes; 0 (a plain sphere) is not laid out here
};

struct LayoutCost {
  std::vector<double> seconds;  // per rank (x fastest): its lay-outs' least time over the repeats
  std::vector<double> cells;    // per rank: the cells its lay-outs report
  std::vector<double> bodies;   // per rank: the bodies it lays out
};

// grid: the flow's cells (lo, spacing, counts; walls on every side, whose cells take what lies
// beyond them); slabs: each rank slab's cell count along x, y, z (FluidGrid's ownership);
// interior cuts: the planes between slabs, for the bodies' owners.
LayoutCost layout_cost(const std::vector<ShapeTemplate>& shapes, const std::vector<BodyPose>& bodies, const Vec3& lo,
                       const Vec3& spacing, const std::array<int, 3>& cells,
                       const std::array<std::vector<double>, 3>& slabs, int repeats);

}  // namespace tessera
