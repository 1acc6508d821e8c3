// SPDX-License-Identifier: MIT
#include "support/dem_fixture.hpp"

namespace tessera::test {

DemRig::DemRig(MPI_Comm comm, const Vec3& lo, const Vec3& hi, const ContactModel& model, const Walls& walls,
               const DemSettings& settings, std::array<int, 3> grid) {
  decomp = std::make_unique<Decomposition>(comm, lo, hi, grid);
  dem = std::make_unique<DemSolver>(*decomp, model, walls, settings);
}

std::ptrdiff_t DemRig::find(std::int64_t id) const {
  const auto& p = dem->particles();
  for (std::size_t i = 0; i < p.owned; ++i)
    if (p.id[i] == id) return static_cast<std::ptrdiff_t>(i);
  return -1;
}

Material make_material(const std::string& name, double density, double youngs, double poisson) {
  Material m;
  m.name = name;
  m.density = density;
  m.youngs_modulus = youngs;
  m.poisson_ratio = poisson;
  return m;
}

}  // namespace tessera::test
