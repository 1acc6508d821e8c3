// SPDX-License-Identifier: MIT
// LAMMPS data files (atom_style sphere): written beds read back identically, on any rank count.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/errors.hpp"
#include "solid/dem_io.hpp"
#include "support/dem_fixture.hpp"

namespace tessera::test {
namespace {

TEST(LammpsData, WriteThenReadRoundTrips) {
  const Material sand = make_material("sand", 2480);
  ContactModel model(LawKind::linear_spring_dashpot, {sand});
  model.set_pair(0, 0, ContactModel::linear_pair(2000, 2000, 0.5, 0.3));
  DemSettings s;
  const std::string path = (std::filesystem::temp_directory_path() / "tessera_roundtrip.data").string();
  DemRig a(MPI_COMM_WORLD, {0, 0, 0}, {0.01, 0.01, 0.01}, model, Walls{}, s);
  for (int i = 0; i < 50; ++i)
    a.dem->add_sphere(100 + i, 0, 2e-4 + 1e-6 * i, {1e-3 + 1.7e-4 * i, 2e-3 + 1.1e-4 * i, 5e-3}, {0.1 * i, 0, -0.2},
                      {0, 3.0 * i, 0});
  write_lammps_data(path, *a.dem);
  MPI_Barrier(MPI_COMM_WORLD);
  DemRig b(MPI_COMM_WORLD, {0, 0, 0}, {0.01, 0.01, 0.01}, model, Walls{}, s);
  EXPECT_EQ(read_lammps_data(path, *b.dem, {0}, "bed.file"), 50);
  const auto& pa = a.dem->particles();
  const auto& pb = b.dem->particles();
  ASSERT_EQ(pa.owned, pb.owned);
  for (std::size_t i = 0; i < pa.owned; ++i) {
    const auto j = b.find(pa.id[i]);
    ASSERT_GE(j, 0);
    EXPECT_EQ(pa.radius[i], pb.radius[j]);
    EXPECT_NEAR(pa.mass[i], pb.mass[j], 1e-15 * pa.mass[i]);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(pa.x[3 * i + k], pb.x[3 * j + k]);
      EXPECT_EQ(pa.v[3 * i + k], pb.v[3 * j + k]);
      EXPECT_EQ(pa.omega[3 * i + k], pb.omega[3 * j + k]);
    }
  }
}

TEST(LammpsData, RejectsBodiesOutsideTheBoxAndUnknownTypes) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const std::string path = (std::filesystem::temp_directory_path() / "tessera_bad.data").string();
  if (rank == 0) {
    std::ofstream o(path);
    o << "title\n\n2 atoms\n2 atom types\n\nAtoms # sphere\n\n1 1 0.001 2500 0.005 0.005 0.005\n2 2 0.001 2500 0.5 "
         "0.005 0.005\n";
  }
  MPI_Barrier(MPI_COMM_WORLD);
  const Material sand = make_material("sand", 2480);
  ContactModel model(LawKind::linear_spring_dashpot, {sand});
  DemSettings s;
  DemRig r(MPI_COMM_WORLD, {0, 0, 0}, {0.01, 0.01, 0.01}, model, Walls{}, s);
  EXPECT_THROW(read_lammps_data(path, *r.dem, {0}, "bed.file"), InputError);  // type 2 unmapped
  DemRig r2(MPI_COMM_WORLD, {0, 0, 0}, {0.01, 0.01, 0.01}, model, Walls{}, s);
  EXPECT_THROW(read_lammps_data(path, *r2.dem, {0, 0}, "bed.file"), InputError);  // body 2 outside
}

}  // namespace
}  // namespace tessera::test
