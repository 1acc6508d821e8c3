// SPDX-License-Identifier: MIT
// The flow scene: air and water in a box, no bodies (issue 4). Dam breaks, drops into pools and
// onto floors. Case sections: domain, fluid, initial, monitors, run, output (docs/cases.md).
//
// Writes DIR/summary.json (quantities, timers, Poisson statistics, dt limits), DIR/series.csv
// (one row per series_interval: time, dt and its limit, Poisson iterations and residual, liquid
// volume, kinetic energy, maximum speed, front position), DIR/fields/fields.xmf (ParaView) and
// DIR/checkpoint.h5 (restart with --restart, also written on SIGTERM / SIGUSR1).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "app/scenes.hpp"
#include "core/errors.hpp"
#include "core/text_file.hpp"

#if defined(TESSERA_HAVE_PETSC)
#include "app/signals.hpp"
#include "fluid/flow_solver.hpp"
#include "fluid/fluid_io.hpp"
#include "tessera_version.hpp"
#endif

namespace tessera {

#if !defined(TESSERA_HAVE_PETSC)

std::unique_ptr<Scene> make_flow_scene(const ConfigNode& root, MPI_Comm, const std::string&) {
  root.fail("scene", "a dry scene: this build has no fluid module (PETSc was not found at configure time)");
}

#else

namespace fs = std::filesystem;
namespace {

int axis_of(const ConfigNode& n, const std::string& key) {
  const std::string a = n.choice(key, {"x", "y", "z"});
  return a[0] - 'x';
}

// An initial liquid region: box, sphere or ellipsoid, with its velocity.
struct LiquidShape {
  enum class Kind { box, ellipsoid } kind = Kind::box;
  Vec3 a, b;  // box: min, max; ellipsoid: centre, semi-axes
  Vec3 velocity;

  bool inside(const Vec3& p) const {
    if (kind == Kind::box) return p.x >= a.x && p.x <= b.x && p.y >= a.y && p.y <= b.y && p.z >= a.z && p.z <= b.z;
    const Vec3 q{(p.x - a.x) / b.x, (p.y - a.y) / b.y, (p.z - a.z) / b.z};
    return dot(q, q) <= 1;
  }
  Vec3 box_min() const { return kind == Kind::box ? a : a - b; }
  Vec3 box_max() const { return kind == Kind::box ? b : a + b; }
};

std::vector<LiquidShape> read_shapes(const ConfigNode& initial) {
  std::vector<LiquidShape> shapes;
  for (const ConfigNode& n : initial.list("liquid")) {
    LiquidShape s;
    const bool box = n.has("box"), sphere = n.has("sphere"), ellipsoid = n.has("ellipsoid");
    if (int(box) + int(sphere) + int(ellipsoid) != 1)
      n.fail("box", "exactly one of box: {min, max}, sphere: {centre, radius}, ellipsoid: {centre, semi_axes}");
    if (box) {
      const ConfigNode b = n.section("box");
      s.kind = LiquidShape::Kind::box;
      s.a = b.vec3("min", Dim::length);
      s.b = b.vec3("max", Dim::length);
      for (int d = 0; d < 3; ++d)
        if (!(s.b[d] > s.a[d])) b.fail("max", "larger than min in every direction");
      s.velocity = b.vec3("velocity", Dim::velocity, Vec3{});
    } else if (sphere) {
      const ConfigNode b = n.section("sphere");
      s.kind = LiquidShape::Kind::ellipsoid;
      s.a = b.vec3("centre", Dim::length);
      const double r = b.real("radius", Dim::length, Range::positive());
      s.b = {r, r, r};
      s.velocity = b.vec3("velocity", Dim::velocity, Vec3{});
    } else {
      const ConfigNode b = n.section("ellipsoid");
      s.kind = LiquidShape::Kind::ellipsoid;
      s.a = b.vec3("centre", Dim::length);
      s.b = b.vec3("semi_axes", Dim::length);
      for (int d = 0; d < 3; ++d)
        if (!(s.b[d] > 0)) b.fail("semi_axes", "positive lengths");
      s.velocity = b.vec3("velocity", Dim::velocity, Vec3{});
    }
    shapes.push_back(s);
  }
  return shapes;
}

BoundaryKind boundary_kind(const ConfigNode& n, const std::string& key) {
  const std::string k = n.choice(key, {"no_slip", "free_slip", "outflow", "periodic"}, "no_slip");
  if (k == "free_slip") return BoundaryKind::free_slip;
  if (k == "outflow") return BoundaryKind::outflow;
  if (k == "periodic") return BoundaryKind::periodic;
  return BoundaryKind::no_slip;
}

FlowSettings read_flow_settings(const ConfigNode& fluid) {
  FlowSettings s;
  const auto cells = fluid.integers("cells", 3, 1, 1 << 16);
  s.cells = {int(cells[0]), int(cells[1]), int(cells[2])};
  const ConfigNode liquid = fluid.section("liquid"), gas = fluid.section("gas");
  s.liquid = {liquid.real("density", Dim::density, Range::positive()),
              liquid.real("viscosity", Dim::viscosity, Range::non_negative())};
  s.gas = {gas.real("density", Dim::density, Range::positive()),
           gas.real("viscosity", Dim::viscosity, Range::non_negative())};
  s.gravity = fluid.vec3("gravity", Dim::acceleration, Vec3{0, 0, -9.81});
  if (const auto b = fluid.optional_section("boundaries")) {
    const char* names[3][2] = {{"x_low", "x_high"}, {"y_low", "y_high"}, {"z_low", "z_high"}};
    for (int d = 0; d < 3; ++d) {
      for (int side = 0; side < 2; ++side) s.boundaries[d][side] = boundary_kind(*b, names[d][side]);
      if ((s.boundaries[d][0] == BoundaryKind::periodic) != (s.boundaries[d][1] == BoundaryKind::periodic))
        b->fail(names[d][1], std::string("periodic on both sides of ") + "xyz"[d] + " or on neither");
    }
  }
  s.wall_model = fluid.choice("wall_model", {"laminar", "spalding"}, "laminar") == "spalding"
                     ? FlowSettings::WallModel::spalding
                     : FlowSettings::WallModel::laminar;
  if (const auto t = fluid.optional_section("time_step")) {
    s.cfl = t->real("cfl", Dim::none, Range{0.0, 0.5, true, false}, s.cfl);
    s.viscous_number = t->real("viscous_number", Dim::none, Range{0.0, 1.0, true, false}, s.viscous_number);
    s.gravity_number = t->real("gravity_number", Dim::none, Range::positive(), s.gravity_number);
    s.dt_max = t->real("max", Dim::time, Range::positive(), s.dt_max);
    s.dt_min = t->real("min", Dim::time, Range::positive(), s.dt_min);
    s.dt_growth = t->real("growth", Dim::none, Range{1.0, 10.0, false, false}, s.dt_growth);
  }
  if (const auto p = fluid.optional_section("poisson")) {
    s.poisson.rtol = p->real("rtol", Dim::none, Range{0.0, 1.0, true, true}, s.poisson.rtol);
    s.poisson.atol = p->real("atol", Dim::none, Range::non_negative(), s.poisson.atol);
    s.poisson.max_iterations = int(p->integer("max_iterations", 1, 100000, s.poisson.max_iterations));
    s.poisson.reuse_preconditioner = int(p->integer("reuse_preconditioner", 1, 100000, s.poisson.reuse_preconditioner));
    s.poisson.petsc_options = p->text("petsc_options", "");
    s.poisson.geometric_multigrid = p->choice("preconditioner", {"multigrid", "petsc"}, "multigrid") == "multigrid";
    if (const auto mg = p->optional_section("multigrid")) {
      s.poisson.pre_sweeps = int(mg->integer("pre_sweeps", 0, 20, s.poisson.pre_sweeps));
      s.poisson.post_sweeps = int(mg->integer("post_sweeps", 0, 20, s.poisson.post_sweeps));
      s.poisson.coarse_sweeps = int(mg->integer("coarse_sweeps", 2, 1000, s.poisson.coarse_sweeps));
      if (s.poisson.pre_sweeps != s.poisson.post_sweeps)
        mg->fail("post_sweeps", "equal to pre_sweeps (CG needs a symmetric preconditioner)");
    }
  }
  return s;
}

class FlowScene final : public Scene {
 public:
  FlowScene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir) {
    (void)case_dir;
    const DomainSpec domain = read_domain(root);
    decomp_ = std::make_unique<Decomposition>(comm, domain.lo, domain.hi, domain.grid);
    flow_ = std::make_unique<FlowSolver>(*decomp_, read_flow_settings(root.section("fluid")));

    if (const auto init = root.optional_section("initial")) {
      shapes_ = read_shapes(*init);
      samples_ = int(init->integer("samples_per_cell_edge", 1, 64, samples_));
    }
    if (const auto mon = root.optional_section("monitors"))
      if (const auto front = mon->optional_section("front")) {
        front_along_ = axis_of(*front, "along");
        front_up_ = axis_of(*front, "up");
        if (front_along_ == front_up_) front->fail("up", "an axis other than `along`");
      }
    const ConfigNode run = root.section("run");
    end_time_ = run.real("end_time", Dim::time, Range::positive());
    if (run.has("max_steps")) max_steps_ = run.integer("max_steps", 1, 1L << 50);
    max_speed_ = run.real("max_speed", Dim::velocity, Range::positive(), 1e3);
    if (const auto out = root.optional_section("output")) {
      field_interval_ = out->real("field_interval", Dim::time, Range::non_negative(), 0.0);
      checkpoint_interval_ = out->real("checkpoint_interval", Dim::time, Range::non_negative(), 0.0);
      series_interval_ = out->real("series_interval", Dim::time, Range::non_negative(), 0.0);
      progress_interval_ = out->real("progress_interval", Dim::time, Range::positive(), 10.0);
    }
  }

  const char* name() const override { return "flow"; }
  nlohmann::json run(const RunOptions& opt, const nlohmann::json& resolved_case) override;

 private:
  void set_initial_state();
  double front_position() const;
  [[noreturn]] void fail(const RunOptions& opt, const std::string& why);

  std::unique_ptr<Decomposition> decomp_;
  std::unique_ptr<FlowSolver> flow_;
  std::vector<LiquidShape> shapes_;
  int samples_ = 8;
  int front_along_ = -1, front_up_ = -1;
  double end_time_ = 0, max_speed_ = 1e3;
  std::optional<long> max_steps_;
  double field_interval_ = 0, checkpoint_interval_ = 0, series_interval_ = 0, progress_interval_ = 10;
};

void FlowScene::set_initial_state() {
  const FluidGrid& g = flow_->grid();
  const FlowSettings& st = flow_->settings();
  flow_->initialize([&](int i, int j, int k) {
    const Vec3 lo{g.lo().x + i * g.h(0), g.lo().y + j * g.h(1), g.lo().z + k * g.h(2)};
    const Vec3 hi{lo.x + g.h(0), lo.y + g.h(1), lo.z + g.h(2)};
    // Only shapes whose bounding box meets the cell are sampled.
    std::vector<const LiquidShape*> near;
    for (const auto& s : shapes_) {
      const Vec3 a = s.box_min(), b = s.box_max();
      if (a.x < hi.x && b.x > lo.x && a.y < hi.y && b.y > lo.y && a.z < hi.z && b.z > lo.z) near.push_back(&s);
    }
    FlowSolver::CellState cs;
    if (near.empty()) return cs;
    const int m = samples_;
    int count = 0;
    Vec3 momentum;
    for (int c = 0; c < m; ++c)
      for (int b = 0; b < m; ++b)
        for (int a = 0; a < m; ++a) {
          const Vec3 p{lo.x + (a + 0.5) / m * g.h(0), lo.y + (b + 0.5) / m * g.h(1), lo.z + (c + 0.5) / m * g.h(2)};
          for (const auto* s : near)
            if (s->inside(p)) {
              ++count;
              momentum += s->velocity;
              break;
            }
        }
    cs.liquid_fraction = double(count) / (double(m) * m * m);
    if (count) {
      // Mass-averaged cell velocity: the liquid part moves, the gas part is at rest.
      const double f = cs.liquid_fraction;
      const double rho = st.gas.density + (st.liquid.density - st.gas.density) * f;
      cs.velocity = (momentum / count) * (st.liquid.density * f / rho);
    }
    return cs;
  });
}

// Front position: h_along times the liquid fraction summed along `along` over the bottom cell row
// (the first cell along `up`), averaged over the third direction (the 0.5 isoline of a
// contiguous water layer; the definition of the interFoam benchmark's front_position.py).
double FlowScene::front_position() const {
  if (front_along_ < 0) return 0;
  const FluidGrid& g = flow_->grid();
  const int third = 3 - front_along_ - front_up_;
  double s = 0;
  if (g.begin(front_up_) == 0)
    for (int k = g.begin(2); k < g.end(2); ++k)
      for (int j = g.begin(1); j < g.end(1); ++j)
        for (int i = g.begin(0); i < g.end(0); ++i) {
          const int idx[3] = {i, j, k};
          if (idx[front_up_] == 0) s += std::clamp(flow_->fraction()[g.at(i, j, k)], 0.0, 1.0);
        }
  return g.reduce_sum(s) * g.h(front_along_) / g.cells()[third];
}

void FlowScene::fail(const RunOptions& opt, const std::string& why) {
  write_flow_checkpoint(opt.output_dir + "/failure.h5", *flow_);
  throw CollectiveRunError("flow: " + why + " at step " + std::to_string(flow_->steps()) +
                           ", t = " + std::to_string(flow_->time()) + " s. Failing state: " + opt.output_dir +
                           "/failure.h5; last good state: " + opt.output_dir + "/checkpoint.h5, if any.");
}

nlohmann::json FlowScene::run(const RunOptions& opt, const nlohmann::json& resolved_case) {
  const FluidGrid& g = flow_->grid();
  MPI_Comm comm = g.comm();
  const bool root = g.rank() == 0;
  const auto wall_start = std::chrono::steady_clock::now();
  auto wall = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count(); };

  if (opt.restart) read_flow_checkpoint(*opt.restart, *flow_);
  if (root) {
    fs::create_directories(opt.output_dir);
    if (!opt.resolved_case_yaml.empty())
      write_file_atomically(opt.output_dir + "/case.resolved.yaml", opt.resolved_case_yaml);
  }
  MPI_Barrier(comm);
  if (!opt.restart) {
    try {
      set_initial_state();  // includes the first projection, which can fail like any other
    } catch (const CollectiveRunError& e) {
      fail(opt, std::string("initial projection: ") + e.what());
    }
  }
  const double volume0 = flow_->liquid_volume();
  const long cells = long(g.cells()[0]) * g.cells()[1] * g.cells()[2];
  if (root && !opt.quiet) {
    const auto& d = decomp_->dims();
    std::printf("tessera %s: scene flow, %d x %d x %d cells, %d ranks (grid %dx%dx%d), Poisson %s\n", kTesseraVersion,
                g.cells()[0], g.cells()[1], g.cells()[2], decomp_->size(), d[0], d[1], d[2],
                flow_->poisson_description().c_str());
    std::fflush(stdout);
  }

  std::ofstream series;
  if (root) {
    const bool append = opt.restart.has_value() && fs::exists(opt.output_dir + "/series.csv");
    series.open(opt.output_dir + "/series.csv", append ? std::ios::app : std::ios::trunc);
    if (!append)
      series << "time,dt,dt_limit,poisson_iterations,poisson_residual,liquid_volume,kinetic_energy,max_speed,"
                "front_position\n";
    series.precision(10);
  }
  FieldSeries fields(opt.output_dir + "/fields");
  auto next_after = [&](double interval) {
    return interval > 0 ? (std::floor(flow_->time() / interval + 1e-9) + 1) * interval : 1e300;
  };
  if (field_interval_ > 0) fields.write(*flow_);
  double next_field = next_after(field_interval_), next_checkpoint = next_after(checkpoint_interval_);
  double next_series = flow_->time();
  double last_progress = 0, peak_speed = flow_->max_speed();
  long poisson_iterations = 0, max_iterations = 0;
  std::map<std::string, long> limits;
  std::string status = "completed";
  const long start_steps = flow_->steps();
  const double loop_start = wall();

  while (flow_->time() < end_time_ * (1 - 1e-12)) {
    if (max_steps_ && flow_->steps() >= *max_steps_) break;
    std::string limit;
    double dt = flow_->stable_dt(limit);
    // Land on output times and the end time (a stretch of up to 1 % saves a tiny last step).
    for (double target : {end_time_, next_field, next_checkpoint}) {
      const double left = target - flow_->time();
      if (left > 0 && dt >= left * 0.99) {
        dt = left;
        limit = "output";
      } else if (left > 0 && dt > 0.5 * left && dt < left) {
        dt = 0.5 * left;
        limit = "output";
      }
    }
    FlowStepStats st;
    try {
      st = flow_->advance(dt);
    } catch (const CollectiveRunError& e) {
      fail(opt, e.what());
    }
    ++limits[limit];
    poisson_iterations += st.poisson.iterations;
    max_iterations = std::max<long>(max_iterations, st.poisson.iterations);
    const bool sample = flow_->time() >= next_series - 1e-12 * end_time_;
    if (sample || flow_->steps() % 20 == 0) {
      const double vmax = flow_->max_speed();
      if (!std::isfinite(vmax) || vmax > max_speed_)
        fail(opt, "maximum speed " + std::to_string(vmax) + " m/s exceeds run.max_speed (" +
                      std::to_string(max_speed_) + " m/s)");
      peak_speed = std::max(peak_speed, vmax);
      if (sample) {
        next_series = series_interval_ > 0 ? next_after(series_interval_) : flow_->time();
        const double volume = flow_->liquid_volume(), ke = flow_->kinetic_energy(), front = front_position();
        if (root)
          series << flow_->time() << ',' << dt << ',' << limit << ',' << st.poisson.iterations << ','
                 << st.poisson.residual << ',' << volume << ',' << ke << ',' << vmax << ',' << front << '\n';
      }
    }
    if (flow_->time() >= next_field - 1e-12 * end_time_) {
      auto t = flow_->timers().scope("output");
      fields.write(*flow_);
      next_field = next_after(field_interval_);
    }
    if (flow_->time() >= next_checkpoint - 1e-12 * end_time_) {
      auto t = flow_->timers().scope("output");
      write_flow_checkpoint(opt.output_dir + "/checkpoint.h5", *flow_);
      next_checkpoint = next_after(checkpoint_interval_);
    }
    if (flow_->steps() % 10 == 0) {
      const RunPoll poll = poll_run(comm, root, wall(), last_progress, progress_interval_);
      if (poll.stop) {
        status = "interrupted";
        break;
      }
      if (poll.progress) {
        last_progress = wall();
        const double drift = (flow_->liquid_volume() - volume0) / volume0;
        const double vmax = flow_->max_speed();
        if (root && !opt.quiet) {
          const double rate = double(flow_->steps() - start_steps) / std::max(1e-9, wall() - loop_start);
          std::printf(
              "step %ld  t %.5g s  dt %.3g (%s)  Poisson %d its  max|u| %.3g m/s  volume drift %.2e  "
              "%.3g steps/s  wall %.1f s\n",
              flow_->steps(), flow_->time(), dt, limit.c_str(), st.poisson.iterations, vmax, drift, rate, wall());
          std::fflush(stdout);
        }
      }
    }
  }
  MPI_Barrier(comm);
  const double loop_seconds = wall() - loop_start;
  {
    auto t = flow_->timers().scope("output");
    write_flow_checkpoint(opt.output_dir + "/checkpoint.h5", *flow_);
    if (field_interval_ > 0 && !fields.written_at(flow_->time())) fields.write(*flow_);
  }
  if (root) series.close();

  const long steps_run = flow_->steps() - start_steps;
  const double volume = flow_->liquid_volume();
  nlohmann::json q;
  q["liquid_volume"] = volume;
  q["liquid_volume_drift"] = volume0 > 0 ? (volume - volume0) / volume0 : 0.0;
  q["kinetic_energy"] = flow_->kinetic_energy();
  q["max_speed"] = flow_->max_speed();
  q["peak_speed"] = peak_speed;
  q["min_liquid_fraction"] = flow_->min_fraction();
  q["max_liquid_fraction"] = flow_->max_fraction();
  q["max_face_divergence"] = flow_->max_face_divergence();
  if (front_along_ >= 0) q["front_position"] = front_position();

  nlohmann::json s;
  s["code_version"] = kTesseraVersion;
  s["scene"] = name();
  s["status"] = status;
  s["ranks"] = decomp_->size();
  s["process_grid"] = decomp_->dims();
  s["cells"] = cells;
  s["steps"] = flow_->steps();
  s["steps_this_run"] = steps_run;
  s["time"] = flow_->time();
  s["poisson"] = {{"solver", flow_->poisson_description()},
                  {"iterations_per_step", steps_run ? double(poisson_iterations) / steps_run : 0.0},
                  {"max_iterations", max_iterations}};
  s["dt_limits"] = limits;
  double wall_s = wall(), loop_s = loop_seconds;
  MPI_Bcast(&wall_s, 1, MPI_DOUBLE, 0, comm);
  MPI_Bcast(&loop_s, 1, MPI_DOUBLE, 0, comm);
  s["wall_seconds"] = wall_s;
  s["loop_seconds"] = loop_s;
  s["cell_steps_per_second_per_core"] = double(cells) * steps_run / std::max(loop_s, 1e-9) / decomp_->size();
  s["quantities"] = q;
  nlohmann::json timers;
  for (const auto& [phase, t] : flow_->timers().reduce(comm))
    timers[phase] = {{"min", t.min}, {"avg", t.avg}, {"max", t.max}};
  s["timers"] = timers;
  s["case"] = resolved_case;
  s["output"] = {{"checkpoint", "checkpoint.h5"},
                 {"series", "series.csv"},
                 {"snapshots", fields.count() ? "fields/fields.xmf" : ""}};
  if (root) write_file_atomically(opt.output_dir + "/summary.json", s.dump(2) + "\n");
  return s;
}

}  // namespace

std::unique_ptr<Scene> make_flow_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir) {
  return std::make_unique<FlowScene>(root, comm, dir);
}

#endif

}  // namespace tessera
