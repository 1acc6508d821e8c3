// SPDX-License-Identifier: MIT
// A small DEM built in code for verification tests: one material table, optional walls, fixed dt.
#pragma once
#include <memory>
#include <vector>

#include "core/decomposition.hpp"
#include "solid/dem_solver.hpp"

namespace tessera::test {

struct DemRig {
  std::unique_ptr<Decomposition> decomp;
  std::unique_ptr<DemSolver> dem;

  DemRig(MPI_Comm comm, const Vec3& lo, const Vec3& hi, const ContactModel& model, const Walls& walls,
         const DemSettings& settings, std::array<int, 3> grid = {0, 0, 0});
  // Body state by global id, on the rank that owns it (nullptr elsewhere).
  std::ptrdiff_t find(std::int64_t id) const;
};

Material make_material(const std::string& name, double density, double youngs = 0, double poisson = 0);

}  // namespace tessera::test
