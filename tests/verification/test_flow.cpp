// SPDX-License-Identifier: MIT
// Verification of the flow solver (src/fluid): kinematic VOF tests, momentum consistency at a
// density ratio of 1000, Taylor-Green decay, hydrostatic rest. References and tolerances are cited
// per test; docs/validation.md has the tables.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <numbers>
#include <sstream>

#include <Eigen/Dense>

#include "app/scene.hpp"
#include "core/config.hpp"
#include "core/decomposition.hpp"
#include "core/errors.hpp"
#include "fluid/flow_solver.hpp"
#include "fluid/plic.hpp"
#include "support/flow_shapes.hpp"
#include "support/taylor_green.hpp"

using namespace tessera;
using tessera::test::sampled_fraction;

namespace {

using Bc = std::array<std::array<BoundaryKind, 2>, 3>;

Bc all(BoundaryKind k) { return {{{k, k}, {k, k}, {k, k}}}; }

bool rank0() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r == 0;
}

template <class F>
void for_owned(const FluidGrid& g, F&& fn) {
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j < g.end(1); ++j)
      for (int i = g.begin(0); i < g.end(0); ++i) fn(i, j, k, g.at(i, j, k));
}

// L1 distance between the current f and a reference (owned cells), times the cell volume.
double l1_error(const FlowSolver& s, const std::vector<double>& ref) {
  const FluidGrid& g = s.grid();
  double e = 0;
  for_owned(g, [&](int, int, int, std::size_t c) { e += std::abs(s.fraction()[c] - ref[c]); });
  return g.reduce_sum(e) * g.cell_volume();
}

// Sets face velocities from a stream function psi(x, y) in the x-y plane: u_f = dpsi/dy and
// v_f = -dpsi/dx as differences of psi at the face's two corners, so the discrete divergence of
// every cell is zero to round-off.
void set_faces_from_stream_function(FlowSolver& s, const std::function<double(double, double)>& psi) {
  const FluidGrid& g = s.grid();
  auto& ufx = s.mutable_face_velocity(0);
  auto& ufy = s.mutable_face_velocity(1);
  for (int k = g.begin(2); k < g.end(2); ++k)
    for (int j = g.begin(1); j <= g.end(1); ++j)
      for (int i = g.begin(0); i <= g.end(0); ++i) {
        const double x = g.lo().x + i * g.h(0), y = g.lo().y + j * g.h(1);
        const std::size_t c = g.at(i, j, k);
        if (j < g.end(1)) ufx[c] = (psi(x, y + g.h(1)) - psi(x, y)) / g.h(1);
        if (i < g.end(0)) ufy[c] = -(psi(x + g.h(0), y) - psi(x, y)) / g.h(0);
      }
}

}  // namespace

// A sphere carried once across a periodic box by a uniform diagonal velocity returns to where it
// started. Liquid volume is conserved to round-off (the split scheme is conservative by
// construction; the reference is 1e-12 relative, the bound), f stays in [0, 1] to
// round-off, and the shape error falls with resolution.
TEST(VofAdvection, TranslatedSphereReturns) {
  double errors[2];
  const int sizes[2] = {16, 32};
  for (int r = 0; r < 2; ++r) {
    const int n = sizes[r];
    Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {1, 1, 1});
    FlowSettings st;
    st.cells = {n, n, n};
    st.boundaries = all(BoundaryKind::periodic);
    st.gravity = {};
    FlowSolver s(decomp, st);
    const Vec3 centre{0.35, 0.4, 0.45};
    auto inside = [&](const Vec3& p) { return dot(p - centre, p - centre) < 0.2 * 0.2; };
    s.initialize([&](int i, int j, int k) {
      return FlowSolver::CellState{sampled_fraction(s.grid(), i, j, k, inside), {1.0, 1.0, 1.0}};
    });
    const std::vector<double> f0 = s.fraction();
    const double v0 = s.liquid_volume();
    const int steps = 4 * n;  // CFL 0.25 per direction, one period
    for (int t = 0; t < steps; ++t) s.advect(1.0 / steps);
    const double v1 = s.liquid_volume();
    EXPECT_LT(std::abs(v1 - v0) / v0, 1e-12) << n;
    EXPECT_GT(s.min_fraction(), -1e-12);
    EXPECT_LT(s.max_fraction(), 1 + 1e-12);
    errors[r] = l1_error(s, f0) / v0;
  }
  if (rank0()) std::printf("translation: relative L1 shape error %.3e (16^3), %.3e (32^3)\n", errors[0], errors[1]);
  EXPECT_LT(errors[1], 0.6 * errors[0]);
  EXPECT_LT(errors[1], 0.05);
}

// Rider & Kothe's single vortex (J. Comput. Phys. 141, 1998): a disc of radius 0.15 at
// (0.5, 0.75) stretched by psi = sin^2(pi x) sin^2(pi y) cos(pi t / T) / pi and brought back at
// t = T. Volume conserved to round-off; the shape error at T falls at least at first order (Youngs
// normals with split advection are first to second order on this test; Rider & Kothe's Table 2).
TEST(VofAdvection, SingleVortexReversal) {
  const double period = 2.0;
  double errors[2];
  const int sizes[2] = {32, 64};
  for (int r = 0; r < 2; ++r) {
    const int n = sizes[r];
    Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {1, 1, 1.0 / n});
    FlowSettings st;
    st.cells = {n, n, 1};
    st.boundaries = all(BoundaryKind::free_slip);
    st.gravity = {};
    FlowSolver s(decomp, st);
    auto inside = [](const Vec3& p) { return (p.x - 0.5) * (p.x - 0.5) + (p.y - 0.75) * (p.y - 0.75) < 0.15 * 0.15; };
    s.initialize([&](int i, int j, int k) {
      return FlowSolver::CellState{sampled_fraction(s.grid(), i, j, k, inside), {}};
    });
    const std::vector<double> f0 = s.fraction();
    const double v0 = s.liquid_volume();
    const int steps = 4 * n;  // max |u| = 1: CFL 0.5 at most
    const double dt = period / steps;
    for (int t = 0; t < steps; ++t) {
      const double time = (t + 0.5) * dt;  // the mid-step velocity field
      set_faces_from_stream_function(s, [&](double x, double y) {
        const double sx = std::sin(M_PI * x), sy = std::sin(M_PI * y);
        return sx * sx * sy * sy * std::cos(M_PI * time / period) / M_PI;
      });
      s.advect(dt);
    }
    EXPECT_LT(std::abs(s.liquid_volume() - v0) / v0, 1e-12) << n;
    EXPECT_GT(s.min_fraction(), -1e-12);
    EXPECT_LT(s.max_fraction(), 1 + 1e-12);
    errors[r] = l1_error(s, f0) * n;  // per unit depth of the one-cell slab
  }
  const double order = std::log2(errors[0] / errors[1]);
  if (rank0())
    std::printf("single vortex T=2: L1 error %.3e (32^2), %.3e (64^2), order %.2f\n", errors[0], errors[1], order);
  EXPECT_GT(order, 1.0);
}

// LeVeque's three-dimensional deformation (SIAM J. Numer. Anal. 33, 1996; the form of Enright et
// al., J. Comput. Phys. 183, 2002): a sphere of radius 0.15 at (0.35, 0.35, 0.35) in the unit box,
// u = 2 sin^2(pi x) sin(2 pi y) sin(2 pi z) g(t), v = -sin(2 pi x) sin^2(pi y) sin(2 pi z) g(t),
// w = -sin(2 pi x) sin(2 pi y) sin^2(pi z) g(t), g = cos(pi t / T), T = 3: stretched into a sheet
// thinner than a cell of 32^3 by T / 2 and brought back at T, where the exact answer is the start.
// The face fluxes are circulations of the vector potential A = (0, -sin^2(pi x) sin(2 pi y)
// sin^2(pi z), sin^2(pi x) sin^2(pi y) sin(2 pi z)) g(t) / pi around each face (its edges'
// integrals in closed form), so every cell's divergence is zero to round-off. Volume conserved to
// round-off, f bounded, and the L1 error at T falls at least at first order from 32^3 to 64^3 (the
// single vortex's bound above). Published L1 errors of other schemes are not compared: the stored
// references did not hold them (issue 18's note).
namespace {

// The L1 error (sum of |f - f0| V) of the deformation test on n^3 cells at T.
double leveque_error(int n) {
  const double period = 3.0, r0 = 0.15;
  const Vec3 centre{0.35, 0.35, 0.35};
  const double pi = M_PI;
  auto s2 = [&](double x) { return std::sin(pi * x) * std::sin(pi * x); };
  // The edges' integrals of A (without g): A_y along y from y0 to y1 at (x, z), A_z along z.
  auto ey = [&](double x, double y0, double y1, double z) {
    return s2(x) * s2(z) * (std::cos(2 * pi * y1) - std::cos(2 * pi * y0)) / (2 * pi * pi);
  };
  auto ez = [&](double x, double y, double z0, double z1) {
    return -s2(x) * s2(y) * (std::cos(2 * pi * z1) - std::cos(2 * pi * z0)) / (2 * pi * pi);
  };
  Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {1, 1, 1});
  FlowSettings st;
  st.cells = {n, n, n};
  st.boundaries = all(BoundaryKind::free_slip);
  st.gravity = {};
  FlowSolver s(decomp, st);
  const FluidGrid& g = s.grid();
  auto inside = [&](const Vec3& p) { return dot(p - centre, p - centre) < r0 * r0; };
  s.initialize([&](int i, int j, int k) {
    const Vec3 c = g.centre(i, j, k);
    if (norm(c - centre) > r0 + g.h(0)) return FlowSolver::CellState{};
    return FlowSolver::CellState{sampled_fraction(g, i, j, k, inside), {}};
  });
  // The face velocities at g = 1: flux through the face over its area.
  std::array<std::vector<double>, 3> unit;
  for (int d = 0; d < 3; ++d) unit[d].assign(g.local_size(), 0.0);
  const double h = g.h(0), area = h * h;
  for (int k = g.begin(2); k <= g.end(2); ++k)
    for (int j = g.begin(1); j <= g.end(1); ++j)
      for (int i = g.begin(0); i <= g.end(0); ++i) {
        const double x0 = i * h, y0 = j * h, z0 = k * h, x1 = x0 + h, y1 = y0 + h, z1 = z0 + h;
        const std::size_t c = g.at(i, j, k);
        if (j < g.end(1) && k < g.end(2))
          unit[0][c] = (ez(x0, y1, z0, z1) - ez(x0, y0, z0, z1) - ey(x0, y0, y1, z1) + ey(x0, y0, y1, z0)) / area;
        if (i < g.end(0) && k < g.end(2)) unit[1][c] = -(ez(x1, y0, z0, z1) - ez(x0, y0, z0, z1)) / area;
        if (i < g.end(0) && j < g.end(1)) unit[2][c] = (ey(x1, y0, y1, z0) - ey(x0, y0, y1, z0)) / area;
      }
  const std::vector<double> f0 = s.fraction();
  const double v0 = s.liquid_volume();
  const int steps = 12 * n;  // max |u| = 2: CFL at most 0.5 per direction
  const double dt = period / steps;
  for (int t = 0; t < steps; ++t) {
    const double gt = std::cos(pi * (t + 0.5) * dt / period);  // the mid-step velocity field
    for (int d = 0; d < 3; ++d) {
      auto& uf = s.mutable_face_velocity(d);
      for (std::size_t c = 0; c < uf.size(); ++c) uf[c] = gt * unit[d][c];
    }
    s.advect(dt);
  }
  EXPECT_LT(std::abs(s.liquid_volume() - v0) / v0, 1e-12) << n;
  EXPECT_GT(s.min_fraction(), -1e-12);
  EXPECT_LT(s.max_fraction(), 1 + 1e-12);
  return l1_error(s, f0);
}

}  // namespace

TEST(VofAdvection, LeVequeDeformationReturns) {
  const double e32 = leveque_error(32), e64 = leveque_error(64);
  const double order = std::log2(e32 / e64);
  if (rank0()) std::printf("LeVeque deformation T=3: L1 error %.3e (32^3), %.3e (64^3), order %.2f\n", e32, e64, order);
  EXPECT_GT(order, 1.0);
}

// The third grid (about 4 minutes; label `slow`, `ctest -R leveque_fine`): 128^3 against 64^3.
TEST(VofAdvection, DISABLED_LeVequeDeformationOn128) {
  const double e64 = leveque_error(64), e128 = leveque_error(128);
  const double order = std::log2(e64 / e128);
  if (rank0()) std::printf("LeVeque deformation T=3: L1 error %.3e (64^3), %.3e (128^3), order %.2f\n", e64, e128, order);
  EXPECT_GT(order, 1.0);
}

// A heavy drop (1000 kg/m^3) moving at 10 m/s through light air (1 kg/m^3) in a periodic box,
// no gravity, no viscosity: the exact solution is a uniform translation, and a scheme that moves
// mass and momentum with the same fluxes keeps the velocity uniform to round-off and the pressure
// flat. Inconsistent schemes blow up here within a few steps (the known failure at ratio 1000).
TEST(MomentumConsistency, HeavyDropTranslatesThroughLightAir) {
  Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {0.02, 0.02, 0.02});
  FlowSettings st;
  st.cells = {24, 24, 24};
  st.boundaries = all(BoundaryKind::periodic);
  st.gravity = {};
  st.liquid = {1000, 0};
  st.gas = {1, 0};
  FlowSolver s(decomp, st);
  const Vec3 centre{0.01, 0.01, 0.01}, velocity{10.0, 4.0, -3.0};
  auto inside = [&](const Vec3& p) { return dot(p - centre, p - centre) < 0.0055 * 0.0055 / 4; };
  s.initialize([&](int i, int j, int k) {
    return FlowSolver::CellState{sampled_fraction(s.grid(), i, j, k, inside), velocity};
  });
  const double v0 = s.liquid_volume();
  double t = 0;
  for (int step = 0; step < 100; ++step) {
    std::string limit;
    const double dt = s.stable_dt(limit);
    s.advance(dt);
    t += dt;
  }
  double worst = 0;
  for_owned(s.grid(), [&](int, int, int, std::size_t c) {
    for (int d = 0; d < 3; ++d) worst = std::max(worst, std::abs(s.velocity(d)[c] - velocity[d]));
  });
  worst = s.grid().reduce_max(worst);
  if (rank0()) std::printf("heavy drop, 100 steps to t = %.3g s: max |u - U| = %.3e m/s\n", t, worst);
  EXPECT_LT(worst, 1e-10);  // 1e-11 of the speed: round-off, not a scheme error
  EXPECT_LT(std::abs(s.liquid_volume() - v0) / v0, 1e-12);
  EXPECT_LT(s.max_speed(), 1.0001 * std::sqrt(dot(velocity, velocity)));
}

// Taylor-Green vortex (single phase, periodic): u = U sin x cos y, v = -U cos x sin y decays as
// exp(-2 nu t). Velocity error in L2 at t = 0.5 on 16^2, 32^2, 64^2 with dt proportional to h^2
// (so the time error falls as fast as a second-order space error): spatial order >= 1.8 (the
// issue's bound; central stress and limited upwind advection are second order away from extrema).
TEST(TaylorGreen, SpatialOrder) {
  const double nu = 0.05, end = 0.5, L = 2 * M_PI;
  double errors[3];
  const int sizes[3] = {16, 32, 64};
  for (int r = 0; r < 3; ++r) {
    const int n = sizes[r];
    Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {L, L, L / n});
    const auto solver = test::taylor_green(decomp, n, nu);
    FlowSolver& s = *solver;
    const FluidGrid& g = s.grid();
    test::advance_taylor_green(s, n, end);
    const double decay = std::exp(-2 * nu * end);
    double e2 = 0;
    for_owned(g, [&](int i, int j, int k, std::size_t c) {
      const Vec3 x = g.centre(i, j, k);
      const double du = s.velocity(0)[c] - decay * std::sin(x.x) * std::cos(x.y);
      const double dv = s.velocity(1)[c] + decay * std::cos(x.x) * std::sin(x.y);
      e2 += du * du + dv * dv;
    });
    errors[r] = std::sqrt(g.reduce_sum(e2) / (double(n) * n));
  }
  const double order1 = std::log2(errors[0] / errors[1]), order2 = std::log2(errors[1] / errors[2]);
  if (rank0())
    std::printf("Taylor-Green L2 velocity error: %.3e %.3e %.3e, orders %.2f %.2f\n", errors[0], errors[1], errors[2],
                order1, order2);
  EXPECT_GE(order2, 1.8);
}

// The energy budget (theory F12a) on the Taylor-Green vortex (nu = 0.05, to t = 0.5): the exact
// kinetic energy decays as exp(-4 nu t), all of it viscous dissipation, so the viscous stage's
// share must be KE0 (exp(-4 nu t) - 1) up to the discretisation's second-order error, and the
// advection's and the projection's shares (energy-neutral in the exact flow) must be small against
// it. Bounds, set from second order before the runs: the viscous share within 2 % of the exact loss
// at 32^2 and 0.5 % at 64^2, the other two together below 5 % and 2 % of it; the three add up to
// the kinetic energy's change to 1e-12 of it (no potential energy without gravity). Measured
// (2026-12-05): viscous off by 2.5e-4 and 1.2e-4 of it (well inside, falling 2x, not 4x: the
// discrete stress's error is not this term's leading one), the others 3.9 % and 0.77 %.
TEST(EnergyBudget, TaylorGreenStagesAgainstTheExactDissipation) {
  const double nu = 0.05, end = 0.5, L = 2 * M_PI;
  const int sizes[2] = {32, 64};
  const double viscous_bound[2] = {0.02, 0.005}, others_bound[2] = {0.05, 0.02};
  for (int r = 0; r < 2; ++r) {
    const int n = sizes[r];
    Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {L, L, L / n});
    const auto solver = test::taylor_green(decomp, n, nu, true);
    FlowSolver& s = *solver;
    const double ke0 = s.kinetic_energy();
    test::advance_taylor_green(s, n, end);
    const double exact = ke0 * (std::exp(-4 * nu * end) - 1);  // < 0
    const auto& b = s.energy_budget();
    const double change = s.kinetic_energy() - ke0;
    if (rank0())
      std::printf("Taylor-Green %d^2 energy budget: advection %.4e, viscous %.4e, projection %.4e J (exact dissipation %.4e; "
                  "viscous off by %.2e of it, the others %.2e; sum - change %.1e)\n",
                  n, b.advection, b.viscous, b.projection, exact, (b.viscous - exact) / exact,
                  (b.advection + b.projection) / exact, b.advection + b.viscous + b.projection - change);
    EXPECT_LT(std::abs(b.viscous - exact), viscous_bound[r] * std::abs(exact));
    EXPECT_LT(std::abs(b.advection + b.projection), others_bound[r] * std::abs(exact));
    EXPECT_LT(std::abs(b.advection + b.viscous + b.projection - change), 1e-12 * std::abs(change));
  }
}

// Water resting under air (ratio 1000) in a closed box, the interface inside a cell row: the
// discrete pressure gradient balances gravity face by face (F10), so the velocities stay at the
// Poisson tolerance. Bound: 1e-9 m/s after 200 steps (the exact state is rest; with rtol 1e-10 the
// residual velocity is ~g dt rtol per step).
// Water and air in a closed 1 cm box of 16^3 cells, the pressure solved to 1e-10.
FlowSettings closed_box(const Vec3& gravity) {
  FlowSettings st;
  st.cells = {16, 16, 16};
  st.boundaries = all(BoundaryKind::no_slip);
  st.poisson.rtol = 1e-10;
  st.gravity = gravity;
  return st;
}

TEST(Hydrostatic, WaterUnderAirStaysAtRest) {
  Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {0.01, 0.01, 0.01});
  FlowSolver s(decomp, closed_box({0, 0, -9.81}));
  s.initialize([&](int i, int j, int k) {
    const double z0 = s.grid().lo().z + k * s.grid().h(2), z1 = z0 + s.grid().h(2), level = 0.0043;
    (void)i, (void)j;
    return FlowSolver::CellState{std::clamp((level - z0) / (z1 - z0), 0.0, 1.0), {}};
  });
  const double v0 = s.liquid_volume();
  for (int t = 0; t < 200; ++t) {
    std::string limit;
    s.advance(s.stable_dt(limit));
  }
  if (rank0()) std::printf("hydrostatic: max speed %.3e m/s after 200 steps, t = %.3g s\n", s.max_speed(), s.time());
  EXPECT_LT(s.max_speed(), 1e-9);
  EXPECT_LT(std::abs(s.liquid_volume() - v0) / v0, 1e-12);
}

// Water under air (1000 : 1) at rest with the gravity turned 30 degrees from the grid's z axis in
// the x-z plane, the interface normal to it: no cell face lies in the interface, each cell holds
// the plane's exact fraction. The projection must hold the fluids at rest (theory F10b: with gravity as
// rho g on the faces, 3.1e-2 m/s appear within 200 steps, 4 times the speed a free fall reaches in
// one step). Bound: 1e-3 of that speed, |g| dt.
TEST(Hydrostatic, TiltedInterfaceStaysAtRest) {
  Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {0.01, 0.01, 0.01});
  const double tilt = 30 * std::numbers::pi / 180;
  FlowSolver s(decomp, closed_box({9.81 * std::sin(tilt), 0, -9.81 * std::cos(tilt)}));
  const Vec3 up{-std::sin(tilt), 0, std::cos(tilt)};  // against the gravity
  const Vec3 centre{0.005, 0.005, 0.0047};
  s.initialize([&](int i, int j, int k) {  // the plane's exact fraction in each cell (PLIC's V(n, alpha))
    const FluidGrid& g = s.grid();
    const Vec3 corner{g.lo().x + i * g.h(0), g.lo().y + j * g.h(1), g.lo().z + k * g.h(2)};
    return FlowSolver::CellState{
        plic::plane_volume(up.x * g.h(0), up.y * g.h(1), up.z * g.h(2), -dot(corner - centre, up)), {}};
  });
  const double v0 = s.liquid_volume();
  double dt = 0, fastest = 0;
  for (int t = 0; t < 200; ++t) {
    std::string limit;
    dt = s.stable_dt(limit);
    s.advance(dt);
    fastest = std::max(fastest, s.max_speed());
  }
  if (rank0())
    std::printf("tilted interface: max speed %.3e m/s over 200 steps (last dt %.3g s, |g| dt %.3g m/s), t = %.3g s\n",
                fastest, dt, 9.81 * dt, s.time());
  EXPECT_LT(fastest, 1e-3 * 9.81 * dt);
  EXPECT_LT(std::abs(s.liquid_volume() - v0) / v0, 1e-12);
}

// The momentum budget of a closed box (theory C8's flow part): with one fluid, the flow's momentum
// changes by gravity's impulse and the walls' (FlowSolver::last_wall_impulse: the wall faces'
// viscous stress, and the wall cell's pressure extrapolated by the hydrostatic gradient its zero
// face acceleration means) and by nothing else: the interior faces' stresses and pressure
// differences cancel in the sum, the advection moves momentum between cells. What is left is F7's
// dilatation term, rho u div(u_f) dt, at the Poisson tolerance. Water swirling in a box, gravity
// turned from z so that every wall carries pressure, no-slip walls but for free-slip ones along y,
// laminar and with the wall law (F8a). Bound: 1e-10 of the largest impulse (measured 1.1e-12: round-off;
// with the dilatation term on the velocity after the earlier sweeps, as F7 had it until 2026-11-30,
// 1.4e-3). A second
// run with air over half the box reports the two-phase residual: F10 gives a cell the mean of its
// faces' accelerations at its own density, which is not conservative where the density jumps.
Vec3 flow_momentum(const FlowSolver& s) {
  const FluidGrid& g = s.grid();
  double p[3] = {0, 0, 0};
  for_owned(g, [&](int, int, int, std::size_t c) {
    for (int d = 0; d < 3; ++d) p[d] += s.density()[c] * g.cell_volume() * s.velocity(d)[c];
  });
  MPI_Allreduce(MPI_IN_PLACE, p, 3, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  return {p[0], p[1], p[2]};
}

double flow_mass(const FlowSolver& s) {
  const FluidGrid& g = s.grid();
  double m = 0;
  for_owned(g, [&](int, int, int, std::size_t c) { m += s.density()[c] * g.cell_volume(); });
  MPI_Allreduce(MPI_IN_PLACE, &m, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  return m;
}

TEST(MomentumBudget, GravityAndWallsAreTheOnlySourcesInAClosedBox) {
  const Vec3 gravity{3.0, -1.5, -9.81};
  for (int run = 0; run < 3; ++run) {  // one fluid laminar, one fluid with the wall law, water under air
    Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {0.01, 0.01, 0.01});
    FlowSettings st = closed_box(gravity);
    st.boundaries[1] = {BoundaryKind::free_slip, BoundaryKind::free_slip};
    if (run == 1) st.wall_model = FlowSettings::WallModel::spalding;
    FlowSolver s(decomp, st);
    s.initialize([&](int i, int j, int k) {
      const Vec3 x = s.grid().centre(i, j, k) * (2 * std::numbers::pi / 0.01);
      const double f = run == 2 ? std::clamp(0.0055 / s.grid().h(2) - k, 0.0, 1.0) : 1.0;
      return FlowSolver::CellState{f, {0.3 * std::sin(x.z) + 0.1, 0.2 * std::cos(x.x), 0.25 * std::sin(x.y) * std::cos(x.x)}};
    });
    const Vec3 p0 = flow_momentum(s);
    const double mass = flow_mass(s);
    Vec3 walls, residual;
    double largest = 0, t = 0, worst = 0;
    for (int n = 0; n < 100; ++n) {
      std::string limit;
      const double dt = s.stable_dt(limit);
      s.advance(dt);
      t += dt;
      walls += s.last_wall_impulse();
      residual = flow_momentum(s) - p0 - (mass * t) * gravity - walls;
      largest = std::max({largest, norm(walls), norm((mass * t) * gravity)});
      worst = std::max(worst, norm(residual));
    }
    if (rank0())
      std::printf("momentum budget, %s: worst residual %.3e kg m/s against impulses up to %.3e (%.1e); walls (%.3e %.3e %.3e), t = %.3g s\n",
                  run == 0 ? "water, laminar walls" : (run == 1 ? "water, wall law" : "water under air"), worst, largest,
                  worst / largest, walls.x, walls.y, walls.z, t);
    if (run < 2) {
      EXPECT_LT(worst, 1e-10 * largest) << run;
    }
  }
}

// Rayleigh-Taylor instability, linear growth (issue 18). A heavy fluid over a light one in a
// quasi-2D box (one wavelength lambda = 1 cm, periodic in x, walls 1 cm above and below), the
// interface displaced by a0 cos(k x), a0 = lambda / 200, at rest. The amplitude is the first Fourier
// mode of the interface height (the liquid column in each x), read while below lambda / 40; sigma
// from acosh(a / a0) / t averaged over that window (from rest the amplitude grows as a0 cosh(sigma t)).
// Reference: the normal mode of two semi-infinite fluids of the same kinematic viscosity
// (Chandrasekhar 1955, Proc. Camb. Phil. Soc. 51, 162), rt_normal_mode_rate below; the walls, 1
// lambda away, lower it by about 1 - tanh(k lambda) = 4e-6. Atwood 0.5 (3 : 1) and 0.998 (1000 : 1),
// 32, 64 and 128 cells per wavelength. Until 2026-12-05 the reference was Duff, Harlow & Hirt's
// (1962) approximation sqrt(A g k + nu^2 k^4) - nu k^2 (55.12 and 78.04 1/s), which leaves out the
// viscous layers at the interface, a term of order k sqrt(nu / sigma) times rho_1 rho_2 / (rho_1 +
// rho_2)^2: 3 % of sigma at 3 : 1, 0.45 % at 1000 : 1; the "deficit" of about 2.5 % at 3 : 1 that
// the grid did not move was that term (docs/validation.md).

// The growth rate s of the normal mode exp(i k x + s t), both fluids of kinematic viscosity nu,
// heavy (rho_2) over light (rho_1), no surface tension: in each fluid w = A e^(-+k z) + B e^(-+q z),
// q^2 = k^2 + s / nu, decaying away from the interface; at the interface w, dw/dz and the
// tangential stress are continuous, and the normal stress jumps by the weight of the displaced
// fluid, g (rho_2 - rho_1) w / s (the pressure from the x momentum: p = rho s A / k above, -rho s
// A / k below). s is the root of the 4 x 4 determinant between 1/2 and 1.2 times the inviscid rate
// (bisection). Checked in the derivation against the inviscid limit and against Lamb's exact
// relation over a vacuum, (s + 2 nu k^2)^2 - g k = 4 nu^2 k^3 q.
double rt_normal_mode_rate(double heavy, double light, double nu, double g, double k) {
  auto det = [&](double s) {
    const double q = std::sqrt(k * k + s / nu), r1 = light, r2 = heavy;
    Eigen::Matrix4d m;
    m << 1, 1, -1, -1,                                                          // w
        k, q, k, q,                                                             // dw/dz
        r1 * 2 * k * k, r1 * (q * q + k * k), -r2 * 2 * k * k, -r2 * (q * q + k * k),  // tangential stress
        -r1 * s / k - 2 * r1 * nu * k + g * (r2 - r1) / s, -2 * r1 * nu * q + g * (r2 - r1) / s,
        -r2 * s / k - 2 * r2 * nu * k, -2 * r2 * nu * q;                        // normal stress
    return m.determinant();
  };
  const double inviscid = std::sqrt((heavy - light) / (heavy + light) * g * k);
  double lo = 0.5 * inviscid, hi = 1.2 * inviscid;
  const double f_lo = det(lo);
  EXPECT_LT(f_lo * det(hi), 0.0) << "no root bracketed";
  for (int i = 0; i < 200 && hi - lo > 1e-12 * inviscid; ++i) {
    const double mid = 0.5 * (lo + hi);
    if ((det(mid) < 0) == (f_lo < 0))
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

double rt_growth_rate(double heavy, double light, int cells, double& reference, double& approximate) {
  const double lambda = 0.01, nu = 1e-6, g = 9.81, k = 2 * std::numbers::pi / lambda;
  Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {lambda, lambda / cells, 2 * lambda});
  FlowSettings st;
  st.cells = {cells, 1, 2 * cells};
  st.boundaries = all(BoundaryKind::no_slip);
  st.boundaries[0] = {BoundaryKind::periodic, BoundaryKind::periodic};
  st.boundaries[1] = {BoundaryKind::free_slip, BoundaryKind::free_slip};
  st.liquid = {heavy, heavy * nu};
  st.gas = {light, light * nu};
  st.gravity = {0, 0, -g};
  st.poisson.rtol = 1e-10;
  FlowSolver s(decomp, st);
  const double a0 = lambda / 200;
  const FluidGrid& grid = s.grid();
  s.initialize([&](int i, int j, int kz) {  // heavy above z = lambda + a0 cos(k x), sampled
    return FlowSolver::CellState{
        sampled_fraction(grid, i, j, kz, [&](const Vec3& p) { return p.z > lambda + a0 * std::cos(k * p.x); }, 16), {}};
  });
  reference = rt_normal_mode_rate(heavy, light, nu, g, k);
  approximate = std::sqrt((heavy - light) / (heavy + light) * g * k + nu * nu * k * k * k * k) - nu * k * k;
  auto amplitude = [&]() {  // first Fourier mode of the light column's height: sum (1 - f) h_z per x
    std::vector<double> height(static_cast<std::size_t>(cells), 0.0);
    for (int kz = grid.begin(2); kz < grid.end(2); ++kz)
      for (int i = grid.begin(0); i < grid.end(0); ++i)
        height[static_cast<std::size_t>(i)] += (1 - s.fraction()[grid.at(i, grid.begin(1), kz)]) * grid.h(2);
    MPI_Allreduce(MPI_IN_PLACE, height.data(), cells, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    double c = 0;
    for (int i = 0; i < cells; ++i) c += height[static_cast<std::size_t>(i)] * std::cos(k * (i + 0.5) * grid.h(0));
    return 2 * c / cells;
  };
  const double start = amplitude();
  double t = 0, sum = 0;
  int samples = 0;
  while (true) {
    std::string limit;
    const double dt = std::min(s.stable_dt(limit), 0.02 / reference);
    s.advance(dt);
    t += dt;
    const double a = amplitude();
    if (a > lambda / 40) break;
    if (a > 2 * start) {  // past the first moments, where the cosh is flat
      sum += std::acosh(a / start) / t;
      ++samples;
    }
  }
  return samples ? sum / samples : 0.0;
}

TEST(RayleighTaylor, LinearGrowthRateAgainstViscousTheory) {
  for (const auto& [heavy, light] : {std::pair{3.0, 1.0}, std::pair{1000.0, 1.0}}) {
    double errors[3];
    int n = 0;
    for (int cells : {32, 64, 128}) {
      double reference = 0, approximate = 0;
      const double sigma = rt_growth_rate(heavy, light, cells, reference, approximate);
      errors[n++] = sigma / reference - 1;
      if (rank0())
        std::printf("Rayleigh-Taylor, %g : %g, %d cells per wavelength: growth rate %.3f 1/s, normal mode %.3f (%+.2f %%); "
                    "Duff-Harlow-Hirt %.3f (%+.2f %%)\n",
                    heavy, light, cells, sigma, reference, 100 * (sigma / reference - 1), approximate,
                    100 * (sigma / approximate - 1));
    }
    // Within 1.5 % on the finest grid: the step (sigma dt <= 0.02) moves the rate by about 0.4 %
    // (measured with sigma dt 0.005), and the cosh fit from rest is the inviscid modes' law; the
    // viscous layers' term the reference adds is 3 % at 3 : 1.
    EXPECT_LT(std::abs(errors[2]), 0.015) << heavy << " : " << light;
  }
}

// Early wetting of a drop hitting a no-slip wall without surface tension (issue 18): the wetted
// radius a(t) = sqrt(3 R V t) (Wagner's theory, Riboux & Gordillo 2014), against the geometric
// sqrt(2 R V t) of a sphere cut by the wall. A quarter of the drop (symmetry planes x = 0, y = 0),
// water in air, R = 1 mm, V = 1 m/s, no gravity, touching at t = 0. a(t): along y = 0 in the wall's
// cell layer, the furthest point where the liquid fraction reaches 1/2 (interpolated between cells);
// peaks: where the pressure in that layer peaks along y = 0 (the largest local maximum).
double wetted_radius_exponent(int cells_per_diameter, std::vector<std::pair<double, double>>& samples,
                              std::vector<std::pair<double, double>>& peaks) {
  const double R = 1e-3, V = 1.0, L = 1.6 * R, H = 2.4 * R;
  const int n = static_cast<int>(std::lround(cells_per_diameter * L / (2 * R)));
  const int nz = static_cast<int>(std::lround(cells_per_diameter * H / (2 * R)));
  Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {L, L, H});
  FlowSettings st;
  st.cells = {n, n, nz};
  st.boundaries = all(BoundaryKind::no_slip);
  st.boundaries[0] = {BoundaryKind::free_slip, BoundaryKind::outflow};
  st.boundaries[1] = {BoundaryKind::free_slip, BoundaryKind::outflow};
  st.boundaries[2] = {BoundaryKind::no_slip, BoundaryKind::outflow};
  st.gravity = {};
  st.poisson.rtol = 1e-8;
  FlowSolver s(decomp, st);
  const FluidGrid& g = s.grid();
  const Vec3 centre{0, 0, R};  // touching the wall at t = 0
  auto inside = [&](const Vec3& p) { return dot(p - centre, p - centre) < R * R; };
  s.initialize([&](int i, int j, int k) {
    const double f = sampled_fraction(g, i, j, k, inside);
    return FlowSolver::CellState{f, {0, 0, f > 0 ? -V : 0.0}};
  });
  double t = 0;
  samples.clear();
  peaks.clear();
  while (t < 0.2 * R / V) {
    std::string limit;
    const double dt = std::min(s.stable_dt(limit), 0.002 * R / V);
    s.advance(dt);
    t += dt;
    double a = 0;
    if (g.begin(1) == 0 && g.begin(2) == 0)  // the rank holding the wall's row along y = 0
      for (int i = g.begin(0); i < g.end(0); ++i) {
        const double f0 = s.fraction()[g.at(i, 0, 0)];
        const double f1 = i + 1 < g.end(0) ? s.fraction()[g.at(i + 1, 0, 0)] : 0.0;
        if (f0 >= 0.5 && f1 < 0.5) a = std::max(a, (i + 0.5 + (f0 - 0.5) / (f0 - f1)) * g.h(0));
      }
    a = g.reduce_max(a);
    // The wall pressure's peak along y = 0 (parabola through the largest cell and its neighbours).
    double peak = -1e300, at = 0;
    if (g.begin(1) == 0 && g.begin(2) == 0)
      for (int i = std::max(g.begin(0), 1); i < std::min(g.end(0), n - 1); ++i) {
        const double pm = s.pressure()[g.at(i - 1, 0, 0)], p0 = s.pressure()[g.at(i, 0, 0)], pp = s.pressure()[g.at(i + 1, 0, 0)];
        if (p0 >= pm && p0 > pp && p0 > peak) {
          peak = p0;
          const double curv = pm - 2 * p0 + pp;
          at = (i + 0.5 + (curv < 0 ? 0.5 * (pm - pp) / curv : 0.0)) * g.h(0);
        }
      }
    const double top = g.reduce_max(peak);
    const double r_peak = g.reduce_max(peak == top ? at : 0.0);
    if (t > 0.02 * R / V) samples.emplace_back(t, a), peaks.emplace_back(t, r_peak);
  }
  // Least squares of a^2 = c R V t: c.
  double num = 0, den = 0;
  for (const auto& [tt, aa] : samples) num += aa * aa * tt, den += tt * tt;
  return num / den / (R * V);
}

// What is checked: a(t) grows as t^(1/2) (the log-log slope of a over the window: measured 0.333,
// 0.458, 0.501 at 20, 40, 80 cells per diameter, converging; bounds 0.25, 0.1, 0.05)
// and ahead of the geometric circle (a^2 / (R V t) above 2: the pressure pushes liquid out ahead of
// the sphere's intersection, as Wagner's theory says). Wagner's prefactor 3 is bracketed, not
// matched: the footprint at f = 1/2 in the wall's cell layer takes in the lamella's foot, which
// runs ahead of the turnover point (measured a^2 = 2.77, 3.26, 3.66 R V t, rising with the grid as
// the layer thins), and the wall pressure's peak, which Wagner's theory puts at the turnover point,
// sits behind it where the lamella's root is not resolved (r^2 = 1.42 (noisy), 2.04, 2.36 R V t,
// rising). On 40 and 80 cells the two lie on either side of 3 (2026-12-03).
void check_wetting(int cells, double slope_bound, bool bracket) {
  std::vector<std::pair<double, double>> samples, peaks;
  const double c = wetted_radius_exponent(cells, samples, peaks);
  double num = 0, den = 0;  // least squares of r_peak^2 = c_peak R V t
  for (const auto& [tt, rr] : peaks) num += rr * rr * tt, den += tt * tt;
  const double c_peak = num / den / (1e-3 * 1.0);
  const auto& [t0, a0] = samples.front();
  const auto& [t1, a1] = samples.back();
  const double slope = std::log(a1 / a0) / std::log(t1 / t0);
  if (rank0()) {
    std::printf("drop on a wall, %d cells per diameter: a^2 = %.3f R V t (Wagner 3, geometric 2), a ~ t^%.3f;", cells, c,
                slope);
    for (std::size_t m = 0; m < samples.size(); m += samples.size() / 5 + 1)
      std::printf("  t %.3f ms a %.3f mm", samples[m].first * 1e3, samples[m].second * 1e3);
    std::printf("\n  the wall pressure's peak: r^2 = %.3f R V t;", c_peak);
    for (std::size_t m = 0; m < peaks.size(); m += peaks.size() / 5 + 1)
      std::printf("  t %.3f ms r %.3f mm", peaks[m].first * 1e3, peaks[m].second * 1e3);
    std::printf("\n");
  }
  EXPECT_NEAR(slope, 0.5, slope_bound) << cells;
  EXPECT_GT(c, 2.0) << cells;
  if (bracket) {
    EXPECT_LT(c_peak, 3.0) << cells;
    EXPECT_GT(c, 3.0) << cells;
  }
}

TEST(DropOnWall, WettedRadiusGrowsAsTheSquareRootOfTime) {
  check_wetting(20, 0.25, false);  // the first samples hold the initial lay-out's footprint (measured 0.33)
  check_wetting(40, 0.1, true);
}

// The finer grid of docs/validation.md (about 50 s), kept out of the default run by its prefix and run
// by the ctest entry test_flow_verification.wetting_fine (label `slow`: `ctest -L slow`).
TEST(DropOnWall, DISABLED_WettedRadiusOn80CellsPerDiameter) { check_wetting(80, 0.05, true); }

// Spalding's law of the wall (fluid.wall_model: spalding). Its inverse against the explicit
// y+(u+) formula (Spalding 1961): factor = y+/u+ to 1e-10 over the sublayer, buffer and log
// regions; 1 in the sublayer (laminar stress); the log law u+ = ln(y+)/0.41 + 5.2 within 1 % at
// u+ = 25. Then in the solver: a water layer sliding at 2 m/s over a no-slip floor (periodic
// sides, no gravity) loses in one step exactly the implicit wall-law drag in its bottom cells and
// nothing elsewhere.
TEST(WallLaw, SpaldingInverseAndBottomCellDrag) {
  const double kappa = 0.41, b = 5.2, nu = 1e-6, utau = 0.05;
  for (double up : {0.5, 3.0, 8.0, 12.0, 25.0}) {
    const double k = kappa * up;
    const double yp = up + std::exp(-kappa * b) * (std::exp(k) - 1 - k - k * k / 2 - k * k * k / 6);
    const double factor = spalding_stress_factor(up * utau, yp * nu / utau, nu);
    EXPECT_NEAR(factor, yp / up, 1e-10 * yp / up) << "u+ " << up;
    if (up == 0.5) {
      EXPECT_NEAR(factor, 1.0, 1e-3);
    }
    if (up == 25.0) {
      EXPECT_NEAR(up, std::log(yp) / kappa + b, 0.01 * up);
    }
  }
  EXPECT_EQ(spalding_stress_factor(0.0, 1e-3, nu), 1.0);

  Decomposition decomp(MPI_COMM_WORLD, {0, 0, 0}, {0.04, 0.04, 0.04});
  FlowSettings st;
  st.cells = {4, 4, 8};
  st.boundaries = all(BoundaryKind::periodic);
  st.boundaries[2] = {BoundaryKind::no_slip, BoundaryKind::free_slip};
  st.gravity = {0, 0, 0};
  st.wall_model = FlowSettings::WallModel::spalding;
  FlowSolver s(decomp, st);
  const double speed = 2.0, dt = 1e-4;
  s.initialize([&](int, int, int) { return FlowSolver::CellState{1.0, {speed, 0, 0}}; });
  s.advance(dt);
  const double h = s.grid().h(2), lam = dt * 2 * 1e-3 / (1000 * h * h);
  const double factor = spalding_stress_factor(speed, h / 2, 1e-6);
  const double expected = speed / (1 + lam * factor);
  if (rank0()) std::printf("wall law: factor %.4f at y = %.3g m, bottom cell %.6f m/s\n", factor, h / 2, expected);
  EXPECT_GT(factor, 10.0);  // y+ ~ 200: a log-region stress, far above the laminar one
  for_owned(s.grid(), [&](int, int, int k, std::size_t c) {
    EXPECT_NEAR(s.velocity(0)[c], k == 0 ? expected : speed, 1e-12) << "k " << k;
    EXPECT_NEAR(s.velocity(2)[c], 0.0, 1e-12);
  });
}

// The hard case (drop-impact seed): the seed's 5.5 mm drop at 9.5 m/s hits a solid floor and a deep
// pool at a density ratio of 1000 with no surface tension, on a coarse grid (cases/drop_impact,
// 32 x 32 x 24 cells, 1.5 ms through the impact). It must run through the impact: no Poisson
// failure, liquid volume conserved to round-off, 0 <= f <= 1 to round-off, and the peak speed
// bounded. Bound: 4 times the impact speed (the thin sheet ejected at the contact line of a drop
// on a floor runs at a few times the impact speed; a blow-up runs away by orders of magnitude).
TEST(DropImpact, SeedDropThroughImpactOnFloorAndPool) {
  for (const char* name : {"seed_floor", "seed_pool"}) {
    Config c = Config::load(std::string(TESSERA_SOURCE_DIR) + "/cases/drop_impact/" + name + ".yaml",
                            {"fluid.cells=[32,32,24]", "run.end_time=1.5 ms", "output.snapshot_interval=0"});
    auto scene = make_scene(c.root(), MPI_COMM_WORLD, ".");
    c.check_unused();
    RunOptions opt;
    opt.output_dir = std::string("drop_impact_") + name;
    opt.quiet = true;
    const auto s = scene->run(opt, {});
    const auto& q = s["quantities"];
    if (rank0())
      std::printf("%s: %ld steps, peak speed %.2f m/s, volume drift %.2e, f in [%.2e, 1 + %.2e]\n", name,
                  s["steps"].get<long>(), q["peak_speed"].get<double>(), q["liquid_volume_drift"].get<double>(),
                  q["min_liquid_fraction"].get<double>(), q["max_liquid_fraction"].get<double>() - 1);
    EXPECT_EQ(s["status"], "completed");
    EXPECT_LT(std::abs(q["liquid_volume_drift"].get<double>()), 1e-12);
    EXPECT_LT(q["peak_speed"].get<double>(), 4 * 9.5);
    EXPECT_GT(q["min_liquid_fraction"].get<double>(), -1e-9);
    EXPECT_LT(q["max_liquid_fraction"].get<double>(), 1 + 1e-9);
  }
}

// Martin & Moyce (1952), Phil. Trans. R. Soc. A 244, 312: the collapse of a water column a x 2a
// (a = 0.146 m) in the 4a x 4a tank, 128^2 cells (cases/dam_break/martin_moyce.yaml). The front
// Z = x/a against T = t sqrt(2g/a), compared at the measured points the tank allows (Z < 3.9).
// Tolerance: mean relative error 0.13. Every simulation of this experiment runs ahead of the
// data (the gate's opening time is not modelled); interFoam on the same grid is 0.094 (128^2) and
// 0.099 (256^2) off, Tessera 0.110 and 0.114 (docs/validation.md), the data of the two column
// widths differ by up to 4 %: 0.13 leaves 2 % of room over Tessera's measured value.
TEST(DamBreak, MartinMoyceFront) {
  Config c =
      Config::load(std::string(TESSERA_SOURCE_DIR) + "/cases/dam_break/martin_moyce.yaml", {"output.snapshot_interval=0"});
  auto scene = make_scene(c.root(), MPI_COMM_WORLD, ".");
  c.check_unused();
  RunOptions opt;
  opt.output_dir = "dam_break_128";
  opt.quiet = true;
  const auto s = scene->run(opt, {});
  EXPECT_LT(std::abs(s["quantities"]["liquid_volume_drift"].get<double>()), 1e-12);
  if (!rank0()) return;
  const double a = 0.146, scale = std::sqrt(2 * 9.81 / a);
  std::vector<double> T, Z;
  std::ifstream series(opt.output_dir + "/series.csv");
  std::string line;
  std::getline(series, line);
  while (std::getline(series, line)) {
    std::stringstream ls(line);
    std::string cell;
    std::vector<std::string> cols;
    while (std::getline(ls, cell, ',')) cols.push_back(cell);
    T.push_back(std::stod(cols[0]) * scale);
    Z.push_back(std::stod(cols[8]) / a);
  }
  std::ifstream ref(std::string(TESSERA_SOURCE_DIR) + "/tests/data/martin_moyce_1952_front.csv");
  double sum = 0;
  int count = 0;
  while (std::getline(ref, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 'T') continue;
    const double Tr = std::stod(line.substr(0, line.find(','))), Zr = std::stod(line.substr(line.find(',') + 1));
    if (Tr <= 0 || Zr > 3.9) continue;
    for (std::size_t i = 1; i < T.size(); ++i)
      if (T[i] >= Tr) {
        const double z = Z[i - 1] + (Z[i] - Z[i - 1]) * (Tr - T[i - 1]) / (T[i] - T[i - 1]);
        sum += std::abs(z - Zr) / Zr;
        ++count;
        break;
      }
  }
  const double mean = sum / count;
  std::printf("dam break 128^2: mean relative front error %.4f over %d measured points\n", mean, count);
  EXPECT_GE(count, 13);
  EXPECT_LT(mean, 0.13);
}

// A Poisson solve that cannot reach its tolerance stops the run with the failing state on disk
// (never a silent step); bad boundary input stops it before anything is written.
TEST(FlowErrors, PoissonFailureStopsWithDumpAndBadInputIsRefused) {
  const std::string dir = "flow_poisson_failure";
  {
    Config c = Config::load(std::string(TESSERA_SOURCE_DIR) + "/cases/drop_impact/seed_pool.yaml",
                            {"fluid.cells=[16,16,12]", "fluid.poisson.max_iterations=1", "fluid.poisson.rtol=1e-14",
                             "output.snapshot_interval=0"});
    auto scene = make_scene(c.root(), MPI_COMM_WORLD, ".");
    c.check_unused();
    RunOptions opt;
    opt.output_dir = dir;
    opt.quiet = true;
    try {
      scene->run(opt, {});
      ADD_FAILURE() << "the run went on without a converged pressure";
    } catch (const CollectiveRunError& e) {
      EXPECT_NE(std::string(e.what()).find("did not converge"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("failure.h5"), std::string::npos) << e.what();
    }
    MPI_Barrier(MPI_COMM_WORLD);
    EXPECT_TRUE(std::ifstream(dir + "/failure.h5").good());
  }
  auto error_of = [](const std::vector<std::string>& sets) -> std::string {
    try {
      Config c = Config::load(std::string(TESSERA_SOURCE_DIR) + "/cases/drop_impact/seed_pool.yaml", sets);
      auto scene = make_scene(c.root(), MPI_COMM_WORLD, ".");
      c.check_unused();
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of({"fluid.boundaries.x_low=periodic"}).find("periodic on both sides"), std::string::npos);
  EXPECT_NE(error_of({"fluid.time_step.cfl=0.7"}).find("cfl"), std::string::npos);
  EXPECT_NE(error_of({"fluid.boundaries.x_low=slippery"}).find("x_low"), std::string::npos);
  EXPECT_NE(error_of({"initial.liquid=[{cube: {min: [0,0,0], max: [1,1,1]}}]"}).find("box"), std::string::npos);
}
