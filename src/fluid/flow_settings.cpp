// SPDX-License-Identifier: MIT
// The case file's `fluid` section, read into FlowSettings (keys: README, section Flow).
#include "fluid/flow_solver.hpp"

namespace tessera {

namespace {

BoundaryKind boundary_kind(const ConfigNode& n, const std::string& key) {
  const std::string k = n.choice(key, {"no_slip", "free_slip", "outflow", "periodic"}, "no_slip");
  if (k == "free_slip") return BoundaryKind::free_slip;
  if (k == "outflow") return BoundaryKind::outflow;
  if (k == "periodic") return BoundaryKind::periodic;
  return BoundaryKind::no_slip;
}

}  // namespace

FlowSettings FlowSettings::from_config(const ConfigNode& fluid) {
  FlowSettings s;
  const auto cells = fluid.integers("cells", 3, 1, 1 << 16);
  s.cells = {int(cells[0]), int(cells[1]), int(cells[2])};
  const ConfigNode liquid = fluid.section("liquid"), gas = fluid.section("gas");
  s.liquid = {liquid.real("density", Dim::density, Range::positive()),
              liquid.real("viscosity", Dim::viscosity, Range::non_negative())};
  s.gas = {gas.real("density", Dim::density, Range::positive()),
           gas.real("viscosity", Dim::viscosity, Range::non_negative())};
  s.gravity = fluid.vec3("gravity", Dim::acceleration, Vec3{0, 0, -9.81});
  s.boundaries = boundaries_from_config(fluid);
  s.wall_model = fluid.choice("wall_model", {"laminar", "spalding"}, "laminar") == "spalding"
                     ? FlowSettings::WallModel::spalding
                     : FlowSettings::WallModel::laminar;
  s.energy_budget = fluid.flag("energy_budget", false);
  if (const auto t = fluid.optional_section("time_step")) {
    s.cfl = t->real("cfl", Dim::none, Range{0.0, 0.5, true, false}, s.cfl);
    s.viscous_number = t->real("viscous_number", Dim::none, Range{0.0, 1.0, true, false}, s.viscous_number);
    s.gravity_number = t->real("gravity_number", Dim::none, Range::positive(), s.gravity_number);
    s.dt_max = t->real("max", Dim::time, Range::positive(), s.dt_max);
    s.dt_min = t->real("min", Dim::time, Range::positive(), s.dt_min);
    s.dt_growth = t->real("growth", Dim::none, Range{1.0, 10.0, false, false}, s.dt_growth);
  }
  s.poisson = poisson_from_config(fluid);
  return s;
}

std::array<std::array<BoundaryKind, 2>, 3> FlowSettings::boundaries_from_config(const ConfigNode& fluid) {
  std::array<std::array<BoundaryKind, 2>, 3> kinds{};  // no-slip everywhere unless given
  if (const auto b = fluid.optional_section("boundaries")) {
    const char* names[3][2] = {{"x_low", "x_high"}, {"y_low", "y_high"}, {"z_low", "z_high"}};
    for (int d = 0; d < 3; ++d) {
      for (int side = 0; side < 2; ++side) kinds[d][side] = boundary_kind(*b, names[d][side]);
      if ((kinds[d][0] == BoundaryKind::periodic) != (kinds[d][1] == BoundaryKind::periodic))
        b->fail(names[d][1], std::string("periodic on both sides of ") + "xyz"[d] + " or on neither");
    }
  }
  return kinds;
}

PoissonSettings FlowSettings::poisson_from_config(const ConfigNode& fluid) {
  PoissonSettings s;
  if (const auto p = fluid.optional_section("poisson")) {
    s.rtol = p->real("rtol", Dim::none, Range{0.0, 1.0, true, true}, s.rtol);
    s.atol = p->real("atol", Dim::none, Range::non_negative(), s.atol);
    s.max_iterations = int(p->integer("max_iterations", 1, 100000, s.max_iterations));
    s.reuse_preconditioner = int(p->integer("reuse_preconditioner", 1, 100000, s.reuse_preconditioner));
    s.petsc_options = p->text("petsc_options", "");
    s.single_reduction = p->flag("single_reduction", s.single_reduction);
    s.geometric_multigrid = p->choice("preconditioner", {"multigrid", "petsc"}, "multigrid") == "multigrid";
    if (const auto mg = p->optional_section("multigrid")) {
      s.pre_sweeps = int(mg->integer("pre_sweeps", 1, 20, s.pre_sweeps));
      s.post_sweeps = int(mg->integer("post_sweeps", 1, 20, s.post_sweeps));
      s.coarse_sweeps = int(mg->integer("coarse_sweeps", 2, 1000, s.coarse_sweeps));
      s.coarse_direct = mg->choice("coarse_solver", {"direct", "sweeps"}, "direct") == "direct";
      s.level_pairs = mg->choice("pairs", {"level", "blocks"}, "level") == "level";
      if (s.pre_sweeps != s.post_sweeps)
        mg->fail("post_sweeps", "equal to pre_sweeps (CG needs a symmetric preconditioner)");
      if (const auto as = mg->optional_section("levels_as_on")) {
        const auto g = as->integers("process_grid", 3, 1, 1 << 20);
        s.levels_as_on.grid = {int(g[0]), int(g[1]), int(g[2])};
        if (const auto cuts = as->optional_section("cuts"))
          for (int d = 0; d < 3; ++d)
            if (cuts->has(std::string(1, "xyz"[d])))
              s.levels_as_on.cuts[d] = cuts->reals(std::string(1, "xyz"[d]), Dim::length);
      }
    }
  }
  return s;
}

}  // namespace tessera
