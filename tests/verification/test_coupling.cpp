// SPDX-License-Identifier: MIT
// The flow-DEM coupling (src/coupling, theory C1-C5) on 1, 2 and 4 ranks, the bodies straddling the
// sub-domain cuts at the middle of the box:
//  - solid fraction: the grid holds the bodies' volume to round-off, and each cell has the same bits
//    as a serial lay-out of every body over the whole grid (no ghost missing, none counted twice);
//  - buoyancy: a body at rest in still water feels rho_w g V (Archimedes) up to the Poisson
//    tolerance; across the free surface g (rho_w V_below + rho_a V_above), within the bound the
//    interface's smearing over three cells allows (2 h g (rho_w - rho_a) A, A the body's largest
//    horizontal section), converging with the grid;
//  - sub-cycling: one coupled step of L DEM sub-steps, fluid force off, is L plain DEM steps bit for
//    bit, contacts included.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

#include "core/errors.hpp"
#include "core/exact_sum.hpp"
#include "coupling/coupled_step.hpp"
#include "coupling/layout_cost.hpp"
#include "solid/rank_load.hpp"
#include "solid/shape.hpp"
#include "support/dem_fixture.hpp"

namespace tessera::test {
namespace {

bool root() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank == 0;
}

constexpr double kBox = 8e-3;
const Vec3 kSemi{1.0e-3, 0.6e-3, 0.5e-3};

ShapeTemplate grain() {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tets;
  ellipsoid_mesh(kSemi, 6, 12, nodes, tets);
  return ShapeTemplate::from_mesh("grain", nodes, tets, 30, 0.2e-3);
}

Quaternion turn(int n) {  // a different orientation per body
  const Vec3 a{std::sin(1.3 * n), std::cos(0.7 * n), 0.5 + std::sin(2.1 * n)};
  const double angle = 0.9 * n + 0.3, s = std::sin(0.5 * angle) / norm(a);
  return {std::cos(0.5 * angle), a.x * s, a.y * s, a.z * s};
}

ContactModel sand_model(double density) {
  ContactModel model(LawKind::linear_spring_dashpot, {make_material("sand", density)});
  model.set_pair(0, 0, ContactModel::linear_pair(1e4, 1e4, 0.5, 0.6));
  return model;
}

FlowSettings water_and_air(int cells) {
  FlowSettings st;
  st.cells = {cells, cells, cells};
  st.liquid = {1000, 1e-3};
  st.gas = {1.0, 1.8e-5};
  st.gravity = {0, 0, -9.81};
  return st;
}

// Liquid fraction of cell k for a flat surface at height z0.
double below(const FluidGrid& g, int k, double z0) {
  const double lo = g.lo().z + k * g.h(2);
  return std::clamp((z0 - lo) / g.h(2), 0.0, 1.0);
}

struct BodyRecord {
  double order, shape, mass, x[3], q[4];
};

// Every rank's owned bodies, on every rank, in canonical order.
std::vector<BodyRecord> all_bodies(const DemSolver& dem) {
  const ParticleStore& p = dem.particles();
  std::vector<BodyRecord> mine(p.owned);
  for (std::size_t i = 0; i < p.owned; ++i) {
    mine[i] = {double(p.order[i]), double(p.shape[i]), p.mass[i], {}, {}};
    for (int k = 0; k < 3; ++k) mine[i].x[k] = p.x[3 * i + k];
    for (int k = 0; k < 4; ++k) mine[i].q[k] = p.q[4 * i + k];
  }
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int n = int(mine.size() * sizeof(BodyRecord) / sizeof(double));
  std::vector<int> counts(size), displs(size);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  int total = 0;
  for (int r = 0; r < size; ++r) displs[r] = total, total += counts[r];
  std::vector<BodyRecord> all(std::size_t(total) * sizeof(double) / sizeof(BodyRecord));
  MPI_Allgatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, MPI_COMM_WORLD);
  std::sort(all.begin(), all.end(), [](const BodyRecord& a, const BodyRecord& b) { return a.order < b.order; });
  return all;
}

// Sand grains (the shape above) in the 8 mm box under gravity, a DEM step of 1 us; bodies to add.
DemRig grain_rig() {
  DemSettings s;
  s.gravity = {0, 0, -9.81};
  s.time_step = 1e-6;
  DemRig rig(MPI_COMM_WORLD, {0, 0, 0}, {kBox, kBox, kBox}, sand_model(2650), Walls{}, s);
  rig.dem->set_shapes({grain()});
  return rig;
}

TEST(SolidFraction, HoldsTheBodiesExactlyWithTheSameBitsOnAnyRankCount) {
  DemRig rig = grain_rig();
  // 27 grains on a 2.5 mm lattice around the box centre, turned: the middle layer sits on the cuts.
  int id = 0, straddling = 0;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k, ++id) {
        const Vec3 x{4e-3 + 2.5e-3 * i + 1e-4 * k, 4e-3 + 2.5e-3 * j - 0.7e-4 * i, 4e-3 + 2.5e-3 * k + 0.5e-4 * j};
        straddling += std::abs(x.x - 4e-3) < 1e-3 || std::abs(x.y - 4e-3) < 1e-3 || std::abs(x.z - 4e-3) < 1e-3;
        rig.dem->add_body(id, 0, 1, x, turn(id), {});
      }
  rig.dem->setup();
  ASSERT_GE(straddling, 19);
  ASSERT_TRUE(rig.dem->shapes()[0].convex);
  FlowSolver flow(*rig.decomp, water_and_air(20));  // h = 0.4 mm: not aligned with the lattice
  flow.initialize([](int, int, int) { return FlowSolver::CellState{1.0, {}}; });
  // Exact poses, then poses rounded to 1 % of the cell (lay-outs reused while unchanged).
  for (double tolerance : {0.0, 0.01}) {
    SolidPhase solid(flow.grid(), *rig.dem, 1000, tolerance);
    solid.update(*rig.dem);
    const SolidPhaseStats st = solid.stats();
    const double v_body = rig.dem->shapes()[0].volume;
    EXPECT_NEAR(st.body_volume, 27 * v_body, 1e-15 * 27 * v_body);
    EXPECT_NEAR(st.solid_volume, st.body_volume, 1e-13 * st.body_volume);
    EXPECT_LE(st.max_fraction, 1.0 + 1e-12);
    EXPECT_GT(st.max_fraction, 0.99);  // some cell lies inside a grain
    // The serial lay-out: every body over the whole grid, in canonical order, kept on owned cells.
    const FluidGrid& g = flow.grid();
    std::vector<double> ref = g.make_field();
    const CellRange cells{g.lo(), {g.h(0), g.h(1), g.h(2)}, {0, 0, 0}, g.cells()};
    CellRasterizer raster;
    const ShapeTemplate& t = rig.dem->shapes()[0];
    for (const BodyRecord& b : all_bodies(*rig.dem)) {
      const auto pose = solid.layout_pose({b.x[0], b.x[1], b.x[2]}, {b.q[0], b.q[1], b.q[2], b.q[3]}, 1);
      if (tolerance == 0) {
        EXPECT_EQ(pose[0], b.x[0]);
      }
      const Quaternion q{pose[3], pose[4], pose[5], pose[6]};
      const Vec3 xb{pose[0], pose[1], pose[2]};
      EXPECT_LE(norm(xb - Vec3{b.x[0], b.x[1], b.x[2]}), 0.5 * std::sqrt(3.0) * tolerance * g.h(0) * (1 + 1e-12));
      // Every node within (1 + sqrt(3)/2) steps of its place (theory C1: the turn moves none more than a step).
      const Quaternion q_exact{b.q[0], b.q[1], b.q[2], b.q[3]};
      for (const Vec3& n : t.nodes) {
        const Vec3 exact = Vec3{b.x[0], b.x[1], b.x[2]} + q_exact.rotate(n);
        EXPECT_LE(norm(xb + Quaternion{pose[3], pose[4], pose[5], pose[6]}.rotate(n) - exact),
                  (1 + 0.5 * std::sqrt(3.0)) * tolerance * g.h(0) * (1 + 1e-9) + 1e-18);
      }
      std::vector<std::pair<std::size_t, double>> pieces;
      auto keep_owned = [&](int i, int j, int k, double v) {
        if (i >= g.begin(0) && i < g.end(0) && j >= g.begin(1) && j < g.end(1) && k >= g.begin(2) && k < g.end(2))
          pieces.emplace_back(g.at(i, j, k), v);
      };
      std::vector<Vec3> world;
      for (const Vec3& n : t.nodes) world.push_back(xb + q.rotate(n));
      Polytope scratch;  // the grain is convex: swept whole (against its tetrahedra: test_tet_clip)
      lay_out_body(t, world, cells, raster, scratch, keep_owned);
      std::stable_sort(pieces.begin(), pieces.end(), [](const auto& a, const auto& c) { return a.first < c.first; });
      for (std::size_t e = 0; e < pieces.size();) {
        double vol = 0;
        const std::size_t c = pieces[e].first;
        for (; e < pieces.size() && pieces[e].first == c; ++e) vol += pieces[e].second;
        ref[c] += vol / g.cell_volume();
      }
    }
    long differ = 0;
    for (int k = g.begin(2); k < g.end(2); ++k)
      for (int j = g.begin(1); j < g.end(1); ++j)
        for (int i = g.begin(0); i < g.end(0); ++i) differ += solid.fraction()[g.at(i, j, k)] != ref[g.at(i, j, k)];
    MPI_Allreduce(MPI_IN_PLACE, &differ, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    EXPECT_EQ(differ, 0) << "cells whose solid fraction differs from the serial lay-out, tolerance " << tolerance;
    // Laid out again without a move: every lay-out reused.
    const long before = solid.layouts_computed();
    solid.update(*rig.dem);
    EXPECT_EQ(solid.layouts_computed(), before);
  }
}

// The scaling model's per-rank counts (solid/rank_load.hpp, computed on one process from the
// bodies' centres) against what each rank holds and lays out: its ghosts, and its owned bodies plus
// the ghosts whose nodes reach its cells (SolidPhase::update skips the others). Grains at 0.3, 1.5,
// 1.6 and 2.9 mm from the cuts: ghosts that reach, ghosts that do not (node reach 1 mm, ghost reach
// 2.1 mm), and bodies no other rank holds.
TEST(SolidFraction, EachRankLaysOutTheBodiesTheScalingModelCounts) {
  DemRig rig = grain_rig();
  const double at[4] = {1.1e-3, 2.5e-3, 4.3e-3, 5.6e-3};
  std::vector<Vec3> xs;
  int id = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k, ++id) {
        xs.push_back({at[i] + 1e-5 * k, at[j] - 1e-5 * i, at[k] + 1e-5 * j});
        rig.dem->add_body(id, 0, 1, xs.back(), turn(id), {});
      }
  rig.dem->setup();
  FlowSolver flow(*rig.decomp, water_and_air(20));
  flow.initialize([](int, int, int) { return FlowSolver::CellState{1.0, {}}; });
  SolidPhase solid(flow.grid(), *rig.dem, 1000);
  solid.update(*rig.dem);
  const ShapeTemplate& t = rig.dem->shapes()[0];
  const std::vector<double> radius(xs.size(), t.bounding_radius), reach(xs.size(), farthest_node(t));
  const auto& dims = rig.decomp->dims();
  // And the contact spheres the DEM's list bins (theory T5b): the owned ones and the ghosts' near a face.
  ElementPlaces elements;
  elements.margin = rig.dem->max_radius() + t.sphere_radius + 3 * rig.dem->skin();
  for (std::size_t b = 0; b < xs.size(); ++b) {
    elements.first.push_back(elements.x.size());
    const Quaternion q = turn(static_cast<int>(b));
    const double qn = std::sqrt(q.norm2());
    const Quaternion qu{q.w / qn, q.x / qn, q.y / qn, q.z / qn};
    for (const Vec3& c : t.spheres) elements.x.push_back(xs[b] + qu.rotate(c)), elements.radius.push_back(t.sphere_radius);
  }
  elements.first.push_back(elements.x.size());
  const RankLoad load = dem_rank_load(xs, radius, {0, 0, 0}, {kBox, kBox, kBox}, dims, rig.decomp->interior_cuts(),
                                      rig.dem->skin(), reach, &elements);
  const auto& c = rig.decomp->coords();
  const auto me = static_cast<std::size_t>(c[0] + dims[0] * (c[1] + dims[1] * c[2]));
  EXPECT_EQ(load.bodies[me], static_cast<double>(rig.dem->particles().owned));
  EXPECT_EQ(load.ghosts[me], static_cast<double>(rig.dem->particles().ghosts));
  EXPECT_EQ(load.laid_out[me], static_cast<double>(solid.layouts_computed() - solid.layouts_elsewhere()));
  EXPECT_EQ(load.owned_elements[me] + load.listed_ghost_elements[me], static_cast<double>(rig.dem->listed_elements()));
  const double ghost_elements = static_cast<double>(rig.dem->particles().ghosts * t.spheres.size());
  EXPECT_EQ(ghost_elements - load.listed_ghost_elements[me], static_cast<double>(rig.dem->ghost_elements_left_out()));
  // The list's work (theory T5c): the elements its one whole listing met, made again here per rank.
  ASSERT_EQ(rig.dem->list_builds(), 1u);
  ASSERT_EQ(rig.dem->list_relists(), 0u);
  EXPECT_GT(load.list_tests[me], 0.0);
  EXPECT_EQ(load.list_tests[me], static_cast<double>(rig.dem->list_tests()));
  if (load.ghosts.size() > 1) {  // some ghost elements listed, some left out
    double listed = 0, all = 0;
    for (std::size_t r = 0; r < load.ghosts.size(); ++r)
      listed += load.listed_ghost_elements[r], all += load.ghosts[r] * static_cast<double>(t.spheres.size());
    EXPECT_GT(listed, 0.1 * all);
    EXPECT_LT(listed, 0.9 * all);
    if (root()) std::printf("%.0f of %.0f ghost elements listed\n", listed, all);
  }
  // Not vacuous on a split grid: some ghosts are laid out, some are not.
  double ghosts = 0, laid_ghosts = 0;
  for (std::size_t r = 0; r < load.ghosts.size(); ++r)
    ghosts += load.ghosts[r], laid_ghosts += load.laid_out[r] - load.bodies[r];
  if (load.ghosts.size() > 1) {
    EXPECT_GT(laid_ghosts, 0);
    EXPECT_LT(laid_ghosts, 0.8 * ghosts);
  }
  if (root()) std::printf("%zu ranks: %.0f ghosts, %.0f of them laid out\n", load.ghosts.size(), ghosts, laid_ghosts);
  // The lay-outs `tessera balance` does on one core for the model (coupling/layout_cost.hpp): each
  // rank's bodies and the cells they report, as this rank's SolidPhase has them (a convex grain: one
  // piece a cell), the cells summing to one rank's whatever the split.
  ASSERT_TRUE(t.convex);
  std::vector<BodyPose> poses;
  for (std::size_t b = 0; b < xs.size(); ++b) {
    const Quaternion q = turn(static_cast<int>(b));
    const double qn = std::sqrt(q.norm2());
    poses.push_back({xs[b], {q.w / qn, q.x / qn, q.y / qn, q.z / qn}, 1});
  }
  const FluidGrid& g = flow.grid();
  const Vec3 h{g.h(0), g.h(1), g.h(2)};
  std::array<std::vector<double>, 3> slabs, whole;
  for (int d = 0; d < 3; ++d) {
    const auto& cuts = rig.decomp->cuts(d);
    slabs[d].assign(static_cast<std::size_t>(dims[d]), 0.0);
    for (int i = 0; i < g.cells()[d]; ++i) {
      const double x = (i + 0.5) * h[d];
      slabs[d][static_cast<std::size_t>(std::upper_bound(cuts.begin() + 1, cuts.end() - 1, x) - (cuts.begin() + 1))] += 1;
    }
    whole[d] = {static_cast<double>(g.cells()[d])};
  }
  const LayoutCost lc = layout_cost(rig.dem->shapes(), poses, {0, 0, 0}, h, g.cells(), slabs, 1);
  const LayoutCost one = layout_cost(rig.dem->shapes(), poses, {0, 0, 0}, h, g.cells(), whole, 1);
  EXPECT_EQ(lc.bodies[me], static_cast<double>(solid.layouts_computed() - solid.layouts_elsewhere()));
  EXPECT_EQ(lc.cells[me], static_cast<double>(solid.cell_entries()));
  double cells = 0;
  for (const double c : lc.cells) cells += c;
  EXPECT_EQ(cells, one.cells[0]);
  EXPECT_GT(lc.seconds[me], 0.0);
}

// A grain at (4, 4, zc) mm in a box of water up to z0 at rest; returns the fluid force and moment
// on it after three flow steps (on every rank), and its volume below z0.
struct Buoyancy {
  Vec3 force, moment;
  double v_below = 0, v_total = 0, section = 0;
};

Buoyancy resting_grain(int cells, double zc, double z0) {
  DemRig rig = grain_rig();
  const Vec3 xc{4e-3 + 1e-5, 4e-3 - 2e-5, zc};
  rig.dem->add_body(0, 0, 1, xc, turn(3), {});
  rig.dem->setup();
  FlowSolver flow(*rig.decomp, water_and_air(cells));
  const FluidGrid& g = flow.grid();
  flow.initialize([&](int, int, int k) { return FlowSolver::CellState{below(g, k, z0), {}}; });
  for (int n = 0; n < 3; ++n) flow.advance(1e-5);
  SolidPhase solid(g, *rig.dem, 1000);
  solid.update(*rig.dem);
  solid.fluid_loads(flow, *rig.dem);
  Buoyancy out;
  const auto& p = rig.dem->particles();
  double fm[6] = {0, 0, 0, 0, 0, 0};
  if (p.owned == 1)
    for (int k = 0; k < 3; ++k) fm[k] = p.f_ext[k], fm[3 + k] = p.t_ext[k];
  MPI_Allreduce(MPI_IN_PLACE, fm, 6, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  out.force = {fm[0], fm[1], fm[2]};
  out.moment = {fm[3], fm[4], fm[5]};
  // The exact reference: the grain's tetrahedra clipped at z0.
  const ShapeTemplate& t = rig.dem->shapes()[0];
  const Quaternion q = turn(3);
  const double qn = std::sqrt(q.norm2());
  const Quaternion qu{q.w / qn, q.x / qn, q.y / qn, q.z / qn};
  for (const auto& tet : t.tetrahedra) {
    Tet w;
    for (int v = 0; v < 4; ++v) w[v] = xc + qu.rotate(t.nodes[tet[v]]);
    std::vector<Tet> part;
    clip_tets({w}, 2, z0, true, part);
    for (const Tet& piece : part) out.v_below += tet_volume(piece);
    out.v_total += tet_volume(w);
  }
  out.section = std::numbers::pi * kSemi.x * kSemi.y;  // the ellipsoid's largest section: a bound
  return out;
}

TEST(FluidForce, SubmergedBodyAtRestFeelsArchimedesBuoyancy) {
  const Buoyancy b = resting_grain(16, 3.7e-3, 6.3e-3);
  const double archimedes = 1000 * 9.81 * b.v_total;
  if (root()) std::printf("  submerged: F = (%.3e, %.3e, %.6e) N, rho g V = %.6e N\n", b.force.x, b.force.y, b.force.z,
              archimedes);
  EXPECT_NEAR(b.force.z, archimedes, 1e-6 * archimedes);
  EXPECT_NEAR(b.force.x, 0, 1e-6 * archimedes);
  EXPECT_NEAR(b.force.y, 0, 1e-6 * archimedes);
  // The centre of buoyancy is the centroid: no moment, to the cell-centre lever arms' resolution
  // (the force density is uniform, so sum V_bc (x_c - x_b) is the volume's first moment about x_b
  // with each piece put at its cell centre: at most V h / 2).
  EXPECT_LE(norm(b.moment), archimedes * 0.5 * kBox / 16);
}

TEST(FluidForce, BodyAcrossTheFreeSurfaceConvergesToArchimedes) {
  const double z0 = 4.3e-3, drho = 1000 - 1.0;
  double last = 1e300;
  for (int cells : {8, 16, 32}) {
    const Buoyancy b = resting_grain(cells, 4.1e-3, z0);
    const double exact = 9.81 * (1000 * b.v_below + 1.0 * (b.v_total - b.v_below));
    const double h = kBox / cells, bound = 2 * h * 9.81 * drho * b.section;
    const double err = std::abs(b.force.z - exact);
    if (root() && last < 1e300) std::printf("  observed order %.2f\n", std::log2(last / err));
    if (root()) std::printf("  h = %.3g mm: F_z = %.6e N, exact %.6e N, error %.3e N (%.2f %% of the bound)\n", h * 1e3, b.force.z,
                exact, err, 100 * err / bound);
    EXPECT_LE(err, bound);
    EXPECT_LT(err, last);
    last = err;
  }
}

// Water streaming at (0.2, -0.1, 0.05) m/s past two grains at rest whose cells overlap, across the
// cuts: the exchange (C4a) and the correction (C4, partly covered cells by C4c or the seed's per-step
// mass average) move momentum between the fluid outside the bodies, sum rho_f (1 - alpha_s) V_c u,
// and the bodies, sum M v, and keep their total to round-off.
// With `drag`, first the projection's cell drag (C4c) as FlowSolver applies it without pressure,
// u <- (u + D U0) / (1 + D): the momentum it takes from the fluid comes back to the bodies in the
// exchange (its implicit reaction), so the total before the drag is the one kept.
void expect_exchange_keeps_momentum(PartialCells partial, double dt, bool drag = false) {
  DemSettings s;
  s.gravity = {0, 0, 0};
  DemRig rig(MPI_COMM_WORLD, {0, 0, 0}, {kBox, kBox, kBox}, sand_model(2650), Walls{}, s);
  rig.dem->set_shapes({grain()});
  rig.dem->add_body(0, 0, 1, {3.9e-3, 4.05e-3, 4.1e-3}, turn(1), {});
  rig.dem->add_body(1, 0, 1, {4.3e-3, 3.7e-3, 3.2e-3}, turn(2), {});
  rig.dem->setup();
  FlowSolver flow(*rig.decomp, water_and_air(16));
  const Vec3 stream{0.2, -0.1, 0.05};
  flow.initialize([&](int, int, int) { return FlowSolver::CellState{1.0, {}}; });
  for (int d = 0; d < 3; ++d) std::fill(flow.mutable_velocity(d).begin(), flow.mutable_velocity(d).end(), stream[d]);
  flow.velocity_changed();  // the cell velocities as they stand (no projection: the stages read cells)
  SolidPhase solid(flow.grid(), *rig.dem, 1000, 0, partial);
  solid.update(*rig.dem);
  auto momentum = [&] {
    const FluidGrid& g = flow.grid();
    std::array<ExactSum, 3> p;
    for (int k = g.begin(2); k < g.end(2); ++k)
      for (int j = g.begin(1); j < g.end(1); ++j)
        for (int i = g.begin(0); i < g.end(0); ++i) {
          const std::size_t c = g.at(i, j, k);
          const double m = flow.density()[c] * g.cell_volume() * std::max(0.0, 1 - solid.fraction()[c]);
          for (int d = 0; d < 3; ++d) p[d].add(m * flow.velocity(d)[c]);
        }
    const ParticleStore& b = rig.dem->particles();
    for (std::size_t n = 0; n < b.owned; ++n)
      for (int d = 0; d < 3; ++d) p[d].add(b.mass[n] * b.v[3 * n + d]);
    ExactSum::all_reduce(p, MPI_COMM_WORLD);
    return Vec3{p[0].value(), p[1].value(), p[2].value()};
  };
  const Vec3 before = momentum();
  if (drag) {
    const CellDrag* cd = solid.drag(flow, *rig.dem, dt);
    ASSERT_NE(cd, nullptr);
    long dragged = 0;
    for (std::size_t c = 0; c < cd->rate.size(); ++c) {
      const double D = cd->rate[c] * dt;
      if (D == 0) continue;
      ++dragged;
      for (int d = 0; d < 3; ++d)
        flow.mutable_velocity(d)[c] = (flow.velocity(d)[c] + D * cd->velocity[d][c]) / (1 + D);
    }
    flow.velocity_changed();
    EXPECT_GT(dragged, 0);
  }
  solid.exchange_momentum(flow, *rig.dem, dt);
  solid.correct_velocity(flow, *rig.dem, dt);
  const Vec3 after = momentum();
  double body_speed = 0;
  const ParticleStore& b = rig.dem->particles();
  for (std::size_t n = 0; n < b.owned; ++n) body_speed = std::max(body_speed, norm(b.vel(n)));
  MPI_Allreduce(MPI_IN_PLACE, &body_speed, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  if (root())
    std::printf("  momentum before (%.9e, %.9e, %.9e), change %.2e kg m/s; bodies now up to %.3e m/s\n", before.x,
                before.y, before.z, norm(after - before), body_speed);
  EXPECT_LE(norm(after - before), 1e-13 * norm(before));
  EXPECT_GT(body_speed, 1e-3);  // the stream dragged the grains
}

TEST(MomentumExchange, FluidAndBodiesKeepTheirMomentum) {
  expect_exchange_keeps_momentum(PartialCells{.per_step = true}, 1e-4);
}

TEST(MomentumExchange, FluidAndBodiesKeepTheirMomentumAtTheRate) {
  // C4c: the correction does what the projection's drag (lambda dt up to SolidPhase::kMaxDrag) left;
  // with lambda dt = kappa nu dt / h^2 alpha / (1 - alpha) = 100 alpha / (1 - alpha) (kappa 25, the
  // 0.5 mm cells, dt 1 s) that is the cells more than half covered.
  expect_exchange_keeps_momentum(PartialCells{.per_step = false, .rate = 25}, 1.0);
}

TEST(MomentumExchange, TheDragsReactionKeepsTheMomentum) {
  // The projection's drag at dt = 1e-3 s (lambda dt = 0.1 alpha / (1 - alpha), below the cap) and its
  // reaction in the exchange; with the inertial part (Ergun's, the stream's 0.23 m/s slip).
  expect_exchange_keeps_momentum(PartialCells{.per_step = false, .rate = 25}, 1e-3, true);
}

TEST(SubCycling, OneFlowStepOfLSubstepsIsLPlainDemStepsBitForBit) {
  // Grains dropped on a floor (contacts with the floor and each other, across the cuts). Fluid force
  // off: the coupled step's DEM stage must be the plain DEM's steps.
  const double dt_dem = std::ldexp(1.0, -20);  // ~0.95 us; dt / L is then exact
  const int L = 16;
  const double dt = dt_dem * L;
  auto build = [&](DemRig& rig) {
    rig.dem->set_shapes({grain()});
    int id = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 2; ++k, ++id)
          rig.dem->add_body(id, 0, 1, {1.6e-3 + 2.4e-3 * i, 1.6e-3 + 2.4e-3 * j, 1.2e-3 + 1.3e-3 * k}, turn(id),
                            {0.05 * std::sin(id), 0.05 * std::cos(id), -0.8});
    rig.dem->setup();
  };
  DemSettings s;
  s.gravity = {0, 0, -9.81};
  s.time_step = dt_dem;
  Walls walls;
  walls.add_box_inside({0, 0, 0}, {kBox, kBox, kBox}, 0);
  DemRig coupled(MPI_COMM_WORLD, {0, 0, 0}, {kBox, kBox, kBox}, sand_model(2650), walls, s);
  DemRig plain(MPI_COMM_WORLD, {0, 0, 0}, {kBox, kBox, kBox}, sand_model(2650), walls, s);
  build(coupled);
  build(plain);
  FlowSolver flow(*coupled.decomp, water_and_air(16));
  flow.initialize([&](int, int, int k) { return FlowSolver::CellState{below(flow.grid(), k, 3e-3), {}}; });
  CouplingSettings cs;
  cs.fluid_force = false;
  CoupledSolver cpl(flow, *coupled.dem, cs);
  cpl.start();
  ASSERT_EQ(cpl.substeps_for(dt), L);
  long contacts = 0;
  for (int n = 0; n < 200; ++n) {
    const CoupledStepStats st = cpl.step(dt);
    ASSERT_EQ(st.substeps, L);
    for (int k = 0; k < L; ++k) plain.dem->step();
    plain.dem->complete_step();
    const DemStats ds = plain.dem->stats();
    contacts += ds.contacts + ds.wall_contacts;
  }
  const auto& a = coupled.dem->particles();
  const auto& b = plain.dem->particles();
  ASSERT_EQ(a.owned, b.owned);
  long differ = 0;
  for (std::size_t i = 0; i < a.owned; ++i) {
    ASSERT_EQ(a.id[i], b.id[i]);
    for (int k = 0; k < 3; ++k)
      differ += a.x[3 * i + k] != b.x[3 * i + k] || a.v[3 * i + k] != b.v[3 * i + k] ||
                a.omega[3 * i + k] != b.omega[3 * i + k];
    for (int k = 0; k < 4; ++k) differ += a.q[4 * i + k] != b.q[4 * i + k];
  }
  MPI_Allreduce(MPI_IN_PLACE, &differ, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(differ, 0);
  if (root()) std::printf("  contacts sampled: %ld\n", contacts);
  EXPECT_GT(contacts, 100) << "the grains must touch the floor and each other";
}

}  // namespace
}  // namespace tessera::test

namespace tessera::test {
namespace {

// A grain released at rest in the middle of a closed box of water; returns its vertical velocity
// after each flow step (on every rank).
std::vector<double> released_grain(MPI_Comm comm, double density, int cells, double dt, int steps,
                                   std::optional<int> substeps = {}) {
  DemSettings s;
  s.gravity = {0, 0, -9.81};
  DemRig rig(comm, {0, 0, 0}, {kBox, kBox, kBox}, sand_model(density), Walls{}, s);
  rig.dem->set_shapes({grain()});
  rig.dem->add_body(0, 0, 1, {4e-3 + 1e-5, 4e-3 - 2e-5, 4.1e-3}, turn(3), {});
  rig.dem->setup();
  FlowSolver flow(*rig.decomp, water_and_air(cells));
  flow.initialize([](int, int, int) { return FlowSolver::CellState{1.0, {}}; });
  CouplingSettings cs;
  cs.substeps = substeps;
  CoupledSolver cpl(flow, *rig.dem, cs);
  cpl.start();
  std::vector<double> w;
  for (int n = 0; n < steps; ++n) {
    cpl.step(dt);
    const auto& p = rig.dem->particles();
    double v = p.owned == 1 ? p.v[2] : 0.0;
    MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_DOUBLE, MPI_SUM, comm);
    w.push_back(v);
  }
  return w;
}

TEST(Coupled, NeutrallyBuoyantGrainStaysPut) {
  // No net force: what moves it is the discretisation alone. 1e-5 m/s is 0.5 % of the speed a
  // 5 % heavier grain reaches in the same time (next test).
  const auto w = released_grain(MPI_COMM_WORLD, 1000, 16, 2e-4, 40);
  double most = 0;
  for (double v : w) most = std::max(most, std::abs(v));
  if (root()) std::printf("  neutral grain: largest |w| %.3e m/s over %zu steps\n", most, w.size());
  EXPECT_LT(most, 1e-5);
}

TEST(Coupled, LightAndHeavyGrainsMoveStablyWithinTheAddedMassBounds) {
  // Released from rest, a body accelerates at (rho_s - rho_w) g / (rho_s + C rho_w) at first. C is
  // its added-mass coefficient (0.5 for a sphere; between about 0.2 and 1 for this 2 : 1.2 : 1
  // ellipsoid), raised over the first 8 ms by the Basset history force: for a sphere from rest
  // under a constant force that force is 18 sqrt(nu t / pi) / r times the added-mass force, 1.4 at
  // 8 ms for this grain's 0.67 mm equivalent radius in water. So the mean acceleration over 40
  // steps of 0.2 ms must lie between the C = 2.5 value and the no-added-mass value
  // (rho_s - rho_w) g / rho_s, and the speed must grow without a sign change in its increments
  // (the added-mass instability of explicit coupling shows as growing oscillations, most of all for
  // light bodies). Densities: 1.05 times the water's (the case), sand, and 0.8 and 0.3 times
  // (stable down to 0.25 on this grid; 0.1 oscillates and grows, and is refused: next test).
  const double dt = 2e-4, g = 9.81;
  for (double rho : {1050.0, 2650.0, 800.0, 300.0}) {
    const auto w = released_grain(MPI_COMM_WORLD, rho, 32, dt, 40);
    const double a = (w.back() - w[3]) / ((w.size() - 4) * dt);  // after the first steps
    const double no_added = (rho - 1000) / rho * -g, most_added = (rho - 1000) / (rho + 2500) * -g;
    const double apparent = ((rho - 1000) * -g / a - rho) / 1000;
    if (root())
      std::printf("  rho %g: mean acceleration %.4f g (apparent C %.2f); bounds %.4f g (C = 2.5) and %.4f g (C = 0)\n",
                  rho, a / g, apparent, most_added / g, no_added / g);
    EXPECT_GT(std::abs(a), std::abs(most_added)) << rho;
    EXPECT_LT(std::abs(a), std::abs(no_added)) << rho;
    EXPECT_GT(a * no_added, 0) << rho;
    for (std::size_t n = 1; n < w.size(); ++n) EXPECT_GT((w[n] - w[n - 1]) * no_added, 0) << rho << " step " << n;
  }
}

TEST(Coupled, TooLightBodiesAreRefusedWithTheReason) {
  DemSettings s;
  DemRig rig(MPI_COMM_WORLD, {0, 0, 0}, {kBox, kBox, kBox}, sand_model(100), Walls{}, s);
  rig.dem->set_shapes({grain()});
  rig.dem->add_body(0, 0, 1, {4e-3, 4e-3, 4e-3}, turn(3), {});
  rig.dem->setup();
  FlowSolver flow(*rig.decomp, water_and_air(16));
  flow.initialize([](int, int, int) { return FlowSolver::CellState{1.0, {}}; });
  try {
    CoupledSolver cpl(flow, *rig.dem, CouplingSettings{});
    FAIL() << "a body of 0.1 times the liquid's density was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("0.3"), std::string::npos) << m;
    EXPECT_NE(m.find("unstable"), std::string::npos) << m;
  }
}

TEST(Coupled, SameMotionOnEveryRankCount) {
  // The run split over the ranks against the same run on each rank alone: equal to the pressure
  // solver's tolerance (the force sums differ in their last bits, the Poisson iterates more).
  const auto split = released_grain(MPI_COMM_WORLD, 1050, 16, 2e-4, 20);
  const auto alone = released_grain(MPI_COMM_SELF, 1050, 16, 2e-4, 20);
  double worst = 0;
  for (std::size_t n = 0; n < split.size(); ++n) worst = std::max(worst, std::abs(split[n] - alone[n]));
  if (root()) std::printf("  largest velocity difference %.3e m/s (speed %.3e m/s)\n", worst, std::abs(alone.back()));
  EXPECT_LE(worst, 1e-4 * std::abs(alone.back()));
}

}  // namespace
}  // namespace tessera::test

namespace tessera::test {
namespace {

// A grain released at rest at height z_release in a closed box of water up to z_surface (air above),
// run until it rests on the floor; the momentum budget (theory C8) after every step.
struct BudgetRun {
  double scale = 0;          // the largest impulse (gravity's on fluid and grain, the walls')
  double worst = 0;          // largest |residual| over the steps (kg m/s)
  double worst_in_flight = 0;  // the same before the grain first touches the floor
  double worst_correction = 0;  // largest |residual of the correction stage| (C4a, C4)
  double peak_momentum = 0;  // the grain's largest |M v|
  Vec3 stage[MomentumBudget::stages];
  double floor_force = 0;    // the floor's mean push on the grain over the last 50 steps (N)
  double rest_speed = 0;     // the grain's speed at the end
  double drift_speed = 0;    // its displacement over the last 50 steps over their duration
  double weight = 0, buoyancy = 0;  // M g, rho_w g V
};

BudgetRun falling_grain(MPI_Comm comm, double z_surface, double z_release, int cells, double dt, int steps,
                        bool conserve = false) {
  DemSettings s;
  s.gravity = {0, 0, -9.81};
  Walls walls;
  walls.add_box_inside({0, 0, 0}, {kBox, kBox, kBox}, 0);
  DemRig rig(comm, {0, 0, 0}, {kBox, kBox, kBox}, sand_model(2650), walls, s);
  rig.dem->set_shapes({grain()});
  rig.dem->add_body(0, 0, 1, {4e-3 + 1e-5, 4e-3 - 2e-5, z_release}, turn(3), {});
  rig.dem->setup();
  FlowSolver flow(*rig.decomp, water_and_air(cells));
  const FluidGrid& g = flow.grid();
  flow.initialize([&](int, int, int k) { return FlowSolver::CellState{below(g, k, z_surface), {}}; });
  CouplingSettings cs;
  cs.conserve_momentum = conserve;
  CoupledSolver cpl(flow, *rig.dem, cs);
  cpl.start();
  cpl.start_momentum_budget();
  BudgetRun out;
  double floor_before = 0;
  auto grain_centre = [&] {
    const auto& p = rig.dem->particles();
    Vec3 x = p.owned == 1 ? Vec3{p.x[0], p.x[1], p.x[2]} : Vec3{};
    MPI_Allreduce(MPI_IN_PLACE, &x.x, 3, MPI_DOUBLE, MPI_SUM, comm);
    return x;
  };
  Vec3 centre_before;
  for (int n = 0; n < steps; ++n) {
    if (n == steps - 50) {
      floor_before = cpl.momentum_budget().body_wall_impulse().z;
      centre_before = grain_centre();
    }
    cpl.step(dt);
    const MomentumBudget& b = cpl.momentum_budget();
    out.scale = std::max({out.scale, norm(b.gravity_impulse()), norm(b.fluid_wall_impulse())});
    out.worst = std::max(out.worst, norm(b.residual()));
    out.worst_correction = std::max(out.worst_correction, norm(b.stage_residual(MomentumBudget::correction)));
    out.peak_momentum = std::max(out.peak_momentum, norm(b.now().bodies));
    if (b.body_wall_impulse().z == 0) out.worst_in_flight = out.worst;
  }
  const MomentumBudget& b = cpl.momentum_budget();
  for (int k = 0; k < MomentumBudget::stages; ++k) out.stage[k] = b.stage_residual(MomentumBudget::Stage(k));
  out.floor_force = (b.body_wall_impulse().z - floor_before) / (50 * dt);
  const double mass = b.now().body_mass;
  out.rest_speed = norm(b.now().bodies) / mass;
  out.drift_speed = norm(grain_centre() - centre_before) / (50 * dt);
  out.weight = mass * 9.81;
  out.buoyancy = 1000 * 9.81 * rig.dem->shapes()[0].volume;
  return out;
}

TEST(MomentumBudget, GrainFallingIntoWaterInAClosedBox) {
  // A sand grain falls 5.5 mm to the floor through water (surface above the box) or through 2 mm
  // of air first (surface at 4 mm), 16^3 cells, 700 steps of 0.2 ms: it lands at about 60-90 ms and
  // comes to rest. Gravity and the walls (the flow's, and the floor's contact on the grain) are the
  // only outside impulses (theory C8).
  //  - Exact, bounded at round-off (1e-6 of the grain's peak momentum over 700 steps of 6 x 6
  //    solves): the correction stage, C4a's exchange and C4 (the fluid gets what the body loses).
  //    The flow's own budget is exact in one fluid (test_flow, MomentumBudget).
  //  - The seed's scheme (the default) does not conserve MICS's virtual fluid, in two places. The
  //    flow step's advection moves momentum into and out of a body's cells that C3 does not give
  //    the body (stage flow_and_bodies), and a body laid out at its new pose takes cells, with their
  //    fluid's momentum, from the fluid outside it and gives others back (stage layout). Both vanish
  //    with no-slip at the surface and scale with the slip in the partly covered cells; here 14 % of
  //    the grain's peak momentum in water (a guard, not a verification: 0.3). With the interface the
  //    flow's own two-phase residual (F10) and the pore liquid's (C7 moves liquid, so density) add
  //    to it (43 %, reported).
  //  - `coupling.conserve_momentum` gives both leaks to the bodies: in water the budget then holds
  //    while the grain falls to 1e-3 of its peak momentum (measured 1.1e-4; the seed's scheme 0.14),
  //    the lay-out's leak comes back in the correction to 1e-3 of itself (measured 2e-4). Once the
  //    grain rests on the floor, a residual builds up: gas where its volume leaves the fluid part
  //    with no liquid to fill it, and F10's residual at that density jump. Until the wall's cells
  //    kept what lies beyond the wall (theory C1) it reached 2.6 % of the peak momentum; since,
  //    0.6 % (the gas equals the volume min(alpha_s, 1) drops where the grain overfills a wall
  //    cell). Bound 0.02: the first part must stay closed. Bounds: what closing the leaks claims,
  //    three orders under them.
  for (bool conserve : {false, true})
    for (double surface : {9e-3, 4e-3}) {
      const BudgetRun r = falling_grain(MPI_COMM_WORLD, surface, 6e-3, 16, 2e-4, 700, conserve);
      const Vec3 returned = r.stage[MomentumBudget::layout] + r.stage[MomentumBudget::correction];
      if (root()) {
        std::printf("  %s, surface %.0f mm: residual up to %.3e kg m/s (%.3f of the grain's peak momentum %.3e; before landing "
                    "%.3e; impulses up to %.3e)\n",
                    conserve ? "conserve_momentum" : "the seed's scheme", surface * 1e3, r.worst, r.worst / r.peak_momentum,
                    r.peak_momentum, r.worst_in_flight, r.scale);
        for (int k = 0; k < MomentumBudget::stages; ++k)
          std::printf("    stage %-16s (%+.3e %+.3e %+.3e)\n", MomentumBudget::name(MomentumBudget::Stage(k)), r.stage[k].x,
                      r.stage[k].y, r.stage[k].z);
        std::printf("    correction stage up to %.3e; at the end %.2e m/s (%.2e m/s over the last 50 steps), the floor's push over "
                    "them %.4e N (M g - rho g V = %.4e N)\n",
                    r.worst_correction, r.rest_speed, r.drift_speed, r.floor_force, r.weight - r.buoyancy);
      }
      EXPECT_LT(r.drift_speed, 1e-3) << "the grain must have landed and come to rest";
      EXPECT_GT(r.floor_force, 0.5 * (r.weight - r.buoyancy)) << "the floor must carry the grain";
      if (!conserve) {
        EXPECT_LT(r.worst_correction, 1e-6 * r.peak_momentum);
        if (surface > kBox) {
          EXPECT_LT(r.worst, 0.3 * r.peak_momentum);
        }
      } else if (surface > kBox) {
        EXPECT_LT(r.worst_in_flight, 1e-3 * r.peak_momentum);
        EXPECT_LT(norm(returned), 1e-3 * norm(r.stage[MomentumBudget::layout]));
        EXPECT_LT(r.worst, 0.02 * r.peak_momentum);
      }
    }
}

}  // namespace
}  // namespace tessera::test
