// SPDX-License-Identifier: MIT
// The Cartesian process grid: shape choice, ownership of points, clamping outside the box.
#include <gtest/gtest.h>

#include "core/decomposition.hpp"
#include "core/errors.hpp"

namespace tessera {
namespace {

TEST(Decomposition, ChoosesLeastSurfaceGrid) {
  EXPECT_EQ(Decomposition::choose_dims(4, {1, 1, 1}, {0, 0, 0}), (std::array<int, 3>{1, 2, 2}));
  EXPECT_EQ(Decomposition::choose_dims(4, {4, 1, 1}, {0, 0, 0}), (std::array<int, 3>{4, 1, 1}));
  EXPECT_EQ(Decomposition::choose_dims(16, {320, 5, 150}, {0, 1, 0}), (std::array<int, 3>{8, 1, 2}));
  EXPECT_EQ(Decomposition::choose_dims(16, {320, 5, 150}, {0, 1, 1}), (std::array<int, 3>{16, 1, 1}));
  EXPECT_EQ(Decomposition::choose_dims(4, {1, 1, 1}, {4, 0, 0}), (std::array<int, 3>{4, 1, 1}));
  EXPECT_THROW(Decomposition::choose_dims(4, {1, 1, 1}, {3, 0, 0}), InputError);
}

TEST(Decomposition, EveryPointHasExactlyOneOwner) {
  Decomposition d(MPI_COMM_WORLD, {0, 0, 0}, {1, 2, 3});
  const Vec3 points[] = {{0, 0, 0}, {0.5, 1, 1.5}, {1, 2, 3}, {0.999, 0.001, 2.5}, {-5, 10, 1}, {0.5, 1.0, 0.75}};
  for (const auto& p : points) {
    int mine = d.owns(p) ? 1 : 0, total = 0;
    MPI_Allreduce(&mine, &total, 1, MPI_INT, MPI_SUM, d.comm());
    EXPECT_EQ(total, 1) << p.x << " " << p.y << " " << p.z;
    EXPECT_EQ(d.owns(p), d.owner_rank(p) == d.rank());
  }
}

}  // namespace
}  // namespace tessera
