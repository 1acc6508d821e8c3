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

TEST(Decomposition, GivenCutsPlaceTheFacesAndFixTheGrid) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  // x split at the given planes (as many as the ranks allow), the rest left to the grid.
  Decomposition::Cuts cuts;
  for (int i = 1; i < size; ++i) cuts[0].push_back(0.1 * i * i);  // uneven: 0.1, 0.4, 0.9
  Decomposition d(MPI_COMM_WORLD, {0, 0, 0}, {1, 2, 3}, {0, 0, 0}, cuts);
  EXPECT_EQ(d.dims()[0], size);
  ASSERT_EQ(d.cuts(0).size(), static_cast<std::size_t>(size + 1));
  EXPECT_EQ(d.cuts(0).front(), 0.0);
  EXPECT_EQ(d.cuts(0).back(), 1.0);
  for (int i = 1; i < size; ++i) EXPECT_EQ(d.cuts(0)[static_cast<std::size_t>(i)], 0.1 * i * i);
  // Every point still has one owner, the one whose slab holds it.
  const Vec3 points[] = {{0.05, 1, 1}, {0.1, 1, 1}, {0.39, 0, 0}, {0.95, 2, 3}, {-1, 1, 1}, {2, 1, 1}};
  for (const auto& p : points) {
    int mine = d.owns(p) ? 1 : 0, total = 0;
    MPI_Allreduce(&mine, &total, 1, MPI_INT, MPI_SUM, d.comm());
    EXPECT_EQ(total, 1);
    if (d.owns(p)) {
      EXPECT_TRUE(p.x < 0 || p.x >= 1 || (p.x >= d.sub_lo().x && p.x < d.sub_hi().x));
    }
  }
}

TEST(Decomposition, RefusesCutsThatDoNotFit) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  // One cut means two slabs along x: refused where the grid cannot have them, and when out of order
  // or outside the box.
  auto make = [](const std::vector<double>& x, std::array<int, 3> grid = {0, 0, 0}) {
    Decomposition::Cuts c;
    c[0] = x;
    Decomposition d(MPI_COMM_WORLD, {0, 0, 0}, {1, 1, 1}, grid, c);
  };
  if (size == 1) {
    EXPECT_THROW(make({0.5}), InputError);
  }
  EXPECT_THROW(make({0.5}, {size + 1, 0, 0}), InputError);  // process_grid disagrees
  EXPECT_THROW(make({1.5}), InputError);
  EXPECT_THROW(make({0.0}), InputError);
  if (size >= 3) {
    EXPECT_THROW(make({0.6, 0.4}), InputError);
  }
}

}  // namespace
}  // namespace tessera
