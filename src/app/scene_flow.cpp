// SPDX-License-Identifier: MIT
// The flow scene: air and water in a box (issue 4). Dam breaks, drops into pools and onto floors.
// Case sections: domain, fluid, initial, monitors, run, output (README, section Flow).
//
// `scene: coupled` is the same scene with bodies in the flow (issue 15, src/coupling): sections
// solid (as a dry scene's), bodies (file: a Tessera checkpoint, e.g. a settled bed; or list: bodies
// one by one) and coupling (substeps, fluid_force); each step is CoupledSolver::step. It also
// writes DIR/snapshots (bodies, grain surfaces), the solid fraction with the fields, DIR/scene.xmf
// (fields and bodies in one time series, ParaView) and DIR/checkpoint_bodies.h5 beside
// DIR/checkpoint.h5. With sections drop and crater it is the drop-impact scene (app/drop_impact.hpp):
// the drop placed over the bed, the crater measured at every snapshot and at the end; with
// bodies.settled_kinetic_energy the run ends once the bodies are at rest.
//
// Writes DIR/summary.json (quantities, timers, Poisson statistics, dt limits), DIR/series.csv
// (one row per series_interval: time, dt and its limit, Poisson iterations and residual, liquid
// volume, kinetic energy, maximum speed, front position), DIR/fields/fields.xmf (ParaView) and
// DIR/checkpoint.h5 (restart with --restart, also written on SIGTERM / SIGUSR1).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>

#include "app/dem_scene.hpp"
#include "app/drop_impact.hpp"
#include "app/run_loop.hpp"
#include "app/scenes.hpp"
#include "core/errors.hpp"
#include "core/exact_sum.hpp"
#include "core/text_file.hpp"

#if defined(TESSERA_HAVE_PETSC)
#include "app/signals.hpp"
#include "coupling/coupled_step.hpp"
#include "fluid/flow_solver.hpp"
#include "fluid/fluid_io.hpp"
#include "solid/dem_io.hpp"
#include "tessera_version.hpp"
#endif

namespace tessera {

#if !defined(TESSERA_HAVE_PETSC)

std::unique_ptr<Scene> make_flow_scene(const ConfigNode& root, MPI_Comm, const std::string&, bool) {
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

std::vector<LiquidShape> read_liquid_shapes(const ConfigNode& initial) {
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

// A body of the coupled scene's `bodies.list`.
struct BodySpec {
  int shape = 1, material = 0;
  Vec3 x, v, omega;
  Quaternion q;
  double density = 0;
};

// The bodies' checkpoint beside the flow's: DIR/checkpoint.h5 -> DIR/checkpoint_bodies.h5.
std::string bodies_path(const std::string& flow_checkpoint) {
  const fs::path p(flow_checkpoint);
  return (p.parent_path() / (p.stem().string() + "_bodies" + p.extension().string())).string();
}

class FlowScene final : public SteppedScene {
 public:
  FlowScene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir, bool coupled) {
    const DomainSpec domain = read_domain(root);
    decomp_ = std::make_unique<Decomposition>(comm, domain.lo, domain.hi, domain.grid);
    flow_ = std::make_unique<FlowSolver>(*decomp_, FlowSettings::from_config(root.section("fluid")));
    if (coupled) read_bodies(root, case_dir);

    if (const auto init = root.optional_section("initial")) {
      shapes_ = read_liquid_shapes(*init);
      samples_ = int(init->integer("samples_per_cell_edge", 1, 64, samples_));
    }
    if (const auto mon = root.optional_section("monitors"))
      if (const auto front = mon->optional_section("front")) {
        front_along_ = axis_of(*front, "along");
        front_up_ = axis_of(*front, "up");
        if (front_along_ == front_up_) front->fail("up", "an axis other than `along`");
      }
    read_loop_keys(root, true);
    poll_every_ = 10;
    max_speed_ = root.section("run").real("max_speed", Dim::velocity, Range::positive(), 1e3);
    if (const auto out = root.optional_section("output")) {
      series_interval_ = out->real("series_interval", Dim::time, Range::non_negative(), 0.0);
      // The name before the scenes shared one output vocabulary (2026-11-29).
      if (out->has("field_interval")) {
        if (out->has("snapshot_interval"))
          out->fail("field_interval", "only one of snapshot_interval and field_interval (its old name)");
        snapshot_interval_ = out->real("field_interval", Dim::time, Range::non_negative());
        deprecated_ = "output.field_interval is deprecated: it is output.snapshot_interval in every scene";
      }
    }
  }

  const char* name() const override { return dem_ ? "coupled" : "flow"; }

 private:
  void read_bodies(const ConfigNode& root, const std::string& case_dir);
  void create_bodies();
  bool check_bodies(const RunOptions& opt);
  std::string body_series();
  void write_scene_index();
  void set_initial_state();
  double front_position() const;
  [[noreturn]] void fail(const RunOptions& opt, const std::string& why);

  // The run loop's hooks (app/run_loop.hpp).
  const Decomposition& decomposition() const override { return *decomp_; }
  void start(const RunOptions& opt) override;
  void begin_output(const RunOptions& opt) override;
  double time() const override { return flow_->time(); }
  long steps() const override { return flow_->steps(); }
  double last_dt() const override { return flow_->last_dt(); }
  void step(const RunOptions& opt) override;
  bool after_step(const RunOptions& opt) override;
  void write_snapshot() override;
  void write_checkpoint(const std::string& path) override {
    if (coupled_ && coupled_->liquid_in_pores())
      write_flow_checkpoint(path, *flow_, {{"liquid_content", &coupled_->liquid().content()}});
    else
      write_flow_checkpoint(path, *flow_);
    if (dem_) tessera::write_checkpoint(bodies_path(path), *dem_, body_extras());
  }
  CheckpointExtras body_extras() const;
  void restore_body_extras(const CheckpointExtras& e);
  std::string progress() override;
  void end_output(const RunOptions& opt) override;
  void summarise(nlohmann::json& s) override;
  PhaseTimers& phase_timers() override { return coupled_ ? coupled_->timers() : flow_->timers(); }

  std::unique_ptr<Decomposition> decomp_;
  std::unique_ptr<FlowSolver> flow_;
  std::vector<LiquidShape> shapes_;
  int samples_ = 8;
  int front_along_ = -1, front_up_ = -1;
  double max_speed_ = 1e3, series_interval_ = 0;
  std::string deprecated_;
  // Run state.
  std::unique_ptr<FieldSeries> fields_;
  std::ofstream series_;
  FlowStepStats last_;
  std::string last_limit_;
  double volume0_ = 0, peak_speed_ = 0, next_series_ = 0;
  long poisson_iterations_ = 0, max_iterations_ = 0;
  std::map<std::string, long> limits_;
  // Coupled scene (null in the flow scene).
  std::unique_ptr<DemSolver> dem_;
  std::unique_ptr<CoupledSolver> coupled_;
  CouplingSettings coupling_;
  std::string bodies_file_;
  std::vector<BodySpec> body_list_;
  double check_interval_ = 0, max_overlap_ratio_ = 0.5;
  Schedule checks_;
  std::unique_ptr<SnapshotSeries> bodies_out_;
  std::string output_dir_;
  int last_substeps_ = 0;
  double free_liquid0_ = 0;  // liquid outside the bodies at the start of this run
  int pore_passes_max_ = 0;  // the liquid stage's largest number of passes and residual (C7), this run
  double pore_residual_max_ = 0;
  // The liquid volume: sum f V_c in the flow scene, the liquid content's sum in the coupled one (C7);
  // the part of it within the cells' fluid part (all of it, to the stage's tolerance).
  double liquid_volume() const {
    return coupled_ && coupled_->liquid_in_pores() ? coupled_->liquid().volume() : flow_->liquid_volume();
  }
  double free_liquid_volume() const {
    return liquid_volume() - coupled_->liquid().volume_in_bodies(coupled_->solid().fraction());
  }
  long substeps_total_ = 0;
  std::array<double, 2> step_range_{std::numeric_limits<double>::infinity(), 0.0};  // coupled steps, this run
  SettleCriterion rest_;  // bodies.settled_kinetic_energy: the run ends when the bodies are at rest
  // The drop-impact scene (sections drop and crater).
  std::optional<DropOnBed> drop_;
  std::optional<CraterMonitor> crater_;
  bool resuming_ = false;  // the first snapshot of a restarted run
};

CheckpointExtras FlowScene::body_extras() const {
  CheckpointExtras e;
  rest_.save(e);
  if (drop_) drop_->save(e);
  if (crater_) crater_->save(e);
  return e;
}

void FlowScene::restore_body_extras(const CheckpointExtras& e) {
  rest_.restore(e);
  if (drop_) drop_->restore(e);
  if (crater_) crater_->restore(e);
}

void FlowScene::read_bodies(const ConfigNode& root, const std::string& case_dir) {
  const ConfigNode solid = root.section("solid");
  ContactModel model(solid);
  Walls walls(solid, model, case_dir);
  const DemSettings ds = DemSettings::from_config(solid);
  const Vec3 gf = flow_->settings().gravity;
  if (norm(ds.gravity - gf) > 1e-12 * (norm(gf) + 1))
    solid.fail("gravity", "the fluid's gravity (the same field acts on fluid and bodies)");
  dem_ = std::make_unique<DemSolver>(*decomp_, std::move(model), std::move(walls), ds);
  dem_->set_shapes(read_shapes(solid, case_dir));
  if (dem_->shapes().empty())
    solid.fail("shapes", "at least one shape template: coupled bodies are made of tetrahedra");
  if (const auto c = root.optional_section("coupling")) coupling_ = CouplingSettings::from_config(*c);
  const ConfigNode b = root.section("bodies");
  if (b.has("file") == b.has("list")) b.fail("file", "exactly one of file (a Tessera checkpoint) and list");
  if (b.has("file")) {
    const fs::path path(b.text("file"));
    bodies_file_ = path.is_absolute() ? path.string() : (fs::path(case_dir) / path).lexically_normal().string();
    if (!fs::is_regular_file(bodies_file_) || fs::path(bodies_file_).extension() != ".h5")
      b.fail("file", "an existing Tessera checkpoint (.h5): " + bodies_file_);
  } else {
    std::vector<int> mats;
    for (const ConfigNode& e : b.list("list")) {
      BodySpec s;
      const std::string shape = e.text("shape");
      s.shape = 0;
      for (std::size_t k = 0; k < dem_->shapes().size(); ++k)
        if (dem_->shapes()[k].name == shape) s.shape = int(k) + 1;
      if (!s.shape) e.fail("shape", "the name of a template in solid.shapes");
      s.material = dem_->model().material_index(e.text("material"), e.key_path("material"));
      mats.push_back(s.material);
      s.x = e.vec3("position", Dim::length);
      s.v = e.vec3("velocity", Dim::velocity, Vec3{});
      s.omega = e.vec3("angular_velocity", Dim::angular_velocity, Vec3{});
      if (const auto o = e.optional_section("orientation")) {  // a turn about an axis, from the template's frame
        const Vec3 axis = o->vec3("axis", Dim::none);
        if (!(norm(axis) > 0)) o->fail("axis", "a non-zero vector");
        const double half = 0.5 * o->real("angle_degrees", Dim::none, Range::closed(-360, 360)) * std::numbers::pi / 180;
        const Vec3 u = axis / norm(axis) * std::sin(half);
        s.q = {std::cos(half), u.x, u.y, u.z};
      }
      s.density = e.real("density", Dim::density, Range::positive(), 0.0);
      body_list_.push_back(s);
    }
    if (body_list_.empty()) b.fail("list", "at least one body");
  }
  rest_ = SettleCriterion(b, false);
  const Vec3 lo = decomp_->global_lo(), hi = decomp_->global_hi();
  if (const auto d = root.optional_section("drop")) drop_.emplace(*d, lo, hi, flow_->settings().liquid.density);
  if (const auto c = root.optional_section("crater")) {
    const double cx = drop_ ? drop_->axis_x() : 0.5 * (lo.x + hi.x), cy = drop_ ? drop_->axis_y() : 0.5 * (lo.y + hi.y);
    double length = 0;  // the longest template: the default ejection distance
    for (const ShapeTemplate& t : dem_->shapes()) length = std::max(length, 2 * t.bounding_radius);
    crater_.emplace(*c, lo, hi, cx, cy, length);
    if (!bodies_file_.empty()) crater_->set_start_positions(read_checkpoint_positions(bodies_file_));
  }
  const ConfigNode run = root.section("run");
  check_interval_ = run.real("check_interval", Dim::time, Range::positive(), 1e-4);
  max_overlap_ratio_ = run.real("max_overlap_ratio", Dim::none, Range{0.0, 2.0, true, false}, max_overlap_ratio_);
}

void FlowScene::create_bodies() {
  if (!bodies_file_.empty()) {
    read_checkpoint(bodies_file_, *dem_);
    dem_->set_clock(0.0, 0);
    dem_->setup(false);
    return;
  }
  std::int64_t id = 0;
  for (const BodySpec& b : body_list_) dem_->add_body(id++, b.material, b.shape, b.x, b.q, b.v, b.omega, b.density);
  dem_->setup(true);
}

// The bodies' columns of series.csv (collective): kinetic energy, largest speed, mean position and
// velocity (exact sums: the same on any rank count for the same state), sub-steps of the last step.
std::string FlowScene::body_series() {
  const DemStats st = dem_->stats();
  const ParticleStore& p = dem_->particles();
  std::array<ExactSum, 6> sums;
  for (std::size_t i = 0; i < p.owned; ++i)
    for (int k = 0; k < 3; ++k) sums[k].add(p.x[3 * i + k]), sums[3 + k].add(p.v[3 * i + k]);
  ExactSum::all_reduce(sums, decomp_->comm());
  std::ostringstream o;
  o.precision(10);
  o << ',' << st.kinetic_translational + st.kinetic_rotational << ',' << st.max_speed;
  for (auto& e : sums) o << ',' << (st.bodies ? e.value() / double(st.bodies) : 0.0);
  o << ',' << last_substeps_;
  return o.str();
}

// Every run.check_interval: the bodies' state is finite, every body is in the box and no overlap
// exceeds the bound; true once the bodies are at rest (bodies.settled_kinetic_energy).
bool FlowScene::check_bodies(const RunOptions& opt) {
  if (!checks_.due(flow_->time(), flow_->last_dt())) return false;
  const DemStats s = dem_->stats();
  const ParticleStore& p = dem_->particles();
  const Vec3 lo = decomp_->global_lo(), hi = decomp_->global_hi();
  std::int64_t outside = std::numeric_limits<std::int64_t>::max();  // lowest id of a body out of the box
  for (std::size_t i = 0; i < p.owned; ++i) {
    const Vec3 x = p.pos(i);
    if (x.x < lo.x || x.x > hi.x || x.y < lo.y || x.y > hi.y || x.z < lo.z || x.z > hi.z) outside = std::min(outside, p.id[i]);
  }
  MPI_Allreduce(MPI_IN_PLACE, &outside, 1, MPI_INT64_T, MPI_MIN, decomp_->comm());
  if (outside != std::numeric_limits<std::int64_t>::max())
    fail(opt, "body " + std::to_string(outside) + " left the box (a wall it passed through, or a blow-up)");
  if (s.finite && s.max_overlap_ratio <= max_overlap_ratio_) return rest_.check(s, flow_->time());
  std::ostringstream m;
  if (!s.finite)
    m << "non-finite body positions or velocities";
  else
    m << "overlap of body " << s.max_overlap_body << " reached " << s.max_overlap_ratio
      << " of its contact radius (run.max_overlap_ratio = " << max_overlap_ratio_
      << "): stiffer contacts, or more DEM sub-steps (coupling.substeps)";
  fail(opt, m.str());
}

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
  write_checkpoint(opt.output_dir + "/failure.h5");
  throw CollectiveRunError("flow: " + why + " at step " + std::to_string(flow_->steps()) +
                           ", t = " + std::to_string(flow_->time()) + " s. Failing state: " + opt.output_dir +
                           "/failure.h5; last good state: " + opt.output_dir + "/checkpoint.h5, if any.");
}

void FlowScene::start(const RunOptions& opt) {
  if (opt.restart) read_flow_checkpoint(*opt.restart, *flow_);
  if (!dem_) return;
  if (opt.restart) {
    restore_body_extras(read_checkpoint(bodies_path(*opt.restart), *dem_));
    dem_->setup(false);
  } else {
    create_bodies();
    if (drop_) {
      const DropShape d = drop_->place(*dem_);
      LiquidShape s;
      s.kind = LiquidShape::Kind::ellipsoid;
      s.a = d.centre, s.b = d.semi_axes, s.velocity = d.velocity;
      shapes_.push_back(s);
    }
    if (crater_) crater_->start(*dem_);
  }
  coupled_ = std::make_unique<CoupledSolver>(*flow_, *dem_, coupling_);
  if (opt.restart && coupling_.liquid_in_pores)
    read_checkpoint_cell_field(*opt.restart, flow_->grid(), "liquid_content", coupled_->mutable_liquid().mutable_content(),
                               "the liquid in the cells' fluid part, theory C7; coupled checkpoints from 2026-11-29 on");
}

void FlowScene::begin_output(const RunOptions& opt) {
  const FluidGrid& g = flow_->grid();
  const bool root = g.rank() == 0;
  if (!opt.restart) {
    try {
      set_initial_state();  // includes the first projection, which can fail like any other
    } catch (const CollectiveRunError& e) {
      fail(opt, std::string("initial projection: ") + e.what());
    }
  }
  if (coupled_) {
    coupled_->start(!opt.restart);  // a restart's velocities were corrected when saved
    if (coupled_->liquid_in_pores()) free_liquid0_ = free_liquid_volume();
  }
  volume0_ = liquid_volume();
  peak_speed_ = flow_->max_speed();
  output_dir_ = opt.output_dir;
  const long bodies = dem_ ? dem_->stats().bodies : 0;  // collective
  if (root && !opt.quiet) {
    const auto& d = decomp_->dims();
    std::printf("tessera %s: scene %s, %d x %d x %d cells, %d ranks (grid %dx%dx%d), Poisson %s\n", kTesseraVersion, name(),
                g.cells()[0], g.cells()[1], g.cells()[2], decomp_->size(), d[0], d[1], d[2],
                flow_->poisson_description().c_str());
    if (coupled_)
      std::printf("  bodies: %ld, DEM stable step %.4g s, sub-steps %s\n", bodies,
                  coupled_->dem_stable_dt(),
                  coupling_.fixed_bodies ? "none (coupling.bodies: fixed)"
                  : coupling_.substeps   ? std::to_string(*coupling_.substeps).c_str()
                                         : "from each flow step's dt");
    if (drop_ && !opt.restart)  // a restart has no new drop: the drop is in the flow's state
      std::printf("  drop: centre %.4g m above the floor, %.4g m above the bed's top\n", shapes_.back().a.z,
                  shapes_.back().a.z - drop_->bed_top_height());
    if (!deprecated_.empty()) std::printf("  warning: %s\n", deprecated_.c_str());
    std::fflush(stdout);
  }
  if (root) {
    const bool append = opt.restart.has_value() && fs::exists(opt.output_dir + "/series.csv");
    series_.open(opt.output_dir + "/series.csv", append ? std::ios::app : std::ios::trunc);
    if (!append)
      series_ << "time,dt,dt_limit,poisson_iterations,poisson_residual,liquid_volume,kinetic_energy,max_speed,"
                 "front_position"
              << (dem_ ? ",body_kinetic_energy,body_max_speed,body_mean_x,body_mean_y,body_mean_z,body_mean_vx,"
                         "body_mean_vy,body_mean_vz,substeps"
                       : "")
              << "\n";
    series_.precision(10);
  }
  fields_ = std::make_unique<FieldSeries>(opt.output_dir + "/fields");
  if (coupled_) {
    fields_->add_field("solid_fraction", &coupled_->solid().fraction());
    if (coupled_->liquid_in_pores()) fields_->add_field("liquid_content", &coupled_->liquid().content());
    bodies_out_ = std::make_unique<SnapshotSeries>(opt.output_dir + "/snapshots");
    bodies_out_->write_loads(coupled_->loads_computed());
    if (crater_)
      crater_->open(opt.output_dir, opt.restart.has_value() && fs::exists(opt.output_dir + "/crater.csv"), root);
    checks_ = Schedule(check_interval_, flow_->time());
  }
  if (snapshot_interval_ > 0) {
    resuming_ = opt.restart.has_value();  // the crater at this time is the stopped run's last row
    write_snapshot();
    resuming_ = false;
  } else if (crater_ && !opt.restart) {
    crater_->sample(*dem_, flow_->time());  // the bed before the drop
  }
  next_series_ = flow_->time();
}

void FlowScene::write_snapshot() {
  fields_->write(*flow_);
  if (!bodies_out_) return;
  coupled_->average_held_loads();  // fixed bodies: their loads over the interval
  bodies_out_->write(*dem_);
  write_scene_index();
  if (crater_ && !resuming_) crater_->sample(*dem_, flow_->time());
}

// DIR/scene.xmf: per snapshot a spatial collection of the fields and the bodies (and the grains'
// surfaces), at the flow's time.
void FlowScene::write_scene_index() {
  if (flow_->grid().rank() != 0) return;
  std::ostringstream x;
  x.precision(17);
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n"
    << "<Grid Name=\"scene\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  const std::size_t n = std::min<std::size_t>(std::size_t(fields_->count()), bodies_out_->count());
  for (std::size_t k = 0; k < n; ++k) {
    x << "<Grid Name=\"step\" GridType=\"Collection\" CollectionType=\"Spatial\">\n<Time Value=\""
      << fields_->time_of(int(k)) << "\"/>\n"
      << fields_->grid_xml(flow_->grid(), int(k), "fields/") << bodies_out_->grid_xml(k, "snapshots/", false)
      << bodies_out_->grid_xml(k, "snapshots/", true) << "</Grid>\n";
  }
  x << "</Grid>\n</Domain>\n</Xdmf>\n";
  write_file_atomically(output_dir_ + "/scene.xmf", x.str());
}

void FlowScene::step(const RunOptions& opt) {
  std::string limit;
  double dt = flow_->stable_dt(limit);
  // Land on output times and the end time (a stretch of up to 1 % saves a tiny last step).
  for (double target : landing_targets()) {
    const double left = target - flow_->time();
    if (left > 0 && dt >= left * 0.99) {
      dt = left;
      limit = "output";
    } else if (left > 0 && dt > 0.5 * left && dt < left) {
      dt = 0.5 * left;
      limit = "output";
    }
  }
  try {
    if (coupled_) {
      const CoupledStepStats cs = coupled_->step(dt);
      last_ = cs.flow;
      last_substeps_ = cs.substeps;
      pore_passes_max_ = std::max(pore_passes_max_, cs.liquid.passes);
      pore_residual_max_ = std::max(pore_residual_max_, cs.liquid.residual);
      substeps_total_ += cs.substeps;
      step_range_[0] = std::min(step_range_[0], dt), step_range_[1] = std::max(step_range_[1], dt);
    } else {
      last_ = flow_->advance(dt);
    }
  } catch (const CollectiveRunError& e) {
    fail(opt, e.what());
  }
  last_limit_ = limit;
  ++limits_[limit];
  poisson_iterations_ += last_.poisson.iterations;
  max_iterations_ = std::max<long>(max_iterations_, last_.poisson.iterations);
}

bool FlowScene::after_step(const RunOptions& opt) {
  const bool at_rest = dem_ && check_bodies(opt);
  const double end = end_time_.value_or(0.0);
  const bool sample = flow_->time() >= next_series_ - 1e-12 * end;
  if (!sample && flow_->steps() % 20 != 0) return at_rest;
  const double vmax = flow_->max_speed();
  if (!std::isfinite(vmax) || vmax > max_speed_)
    fail(opt, "maximum speed " + std::to_string(vmax) + " m/s exceeds run.max_speed (" + std::to_string(max_speed_) +
                  " m/s)");
  peak_speed_ = std::max(peak_speed_, vmax);
  if (sample) {
    next_series_ = series_interval_ > 0 ? Schedule(series_interval_, flow_->time()).next() : flow_->time();
    const double volume = liquid_volume(), ke = flow_->kinetic_energy(), front = front_position();
    std::string bodies;
    if (dem_) bodies = body_series();
    if (flow_->grid().rank() == 0)
      series_ << flow_->time() << ',' << last_.dt << ',' << last_limit_ << ',' << last_.poisson.iterations << ','
              << last_.poisson.residual << ',' << volume << ',' << ke << ',' << vmax << ',' << front << bodies
              << std::endl;  // flushed: a batch job's series can be followed while it runs
  }
  return at_rest;
}

std::string FlowScene::progress() {
  const double drift = (liquid_volume() - volume0_) / volume0_;
  const double vmax = flow_->max_speed();
  char line[200];
  std::snprintf(line, sizeof line, "dt %.3g (%s)  Poisson %d its  max|u| %.3g m/s  volume drift %.2e", last_.dt,
                last_limit_.c_str(), last_.poisson.iterations, vmax, drift);
  if (!dem_) return line;
  const DemStats b = dem_->stats();
  char more[160];
  std::snprintf(more, sizeof more, "  L %d  bodies KE %.3g J  max|v| %.3g m/s", last_substeps_,
                b.kinetic_translational + b.kinetic_rotational, b.max_speed);
  return std::string(line) + more;
}

void FlowScene::end_output(const RunOptions& opt) {
  write_checkpoint(opt.output_dir + "/checkpoint.h5");
  if (snapshot_interval_ > 0 && !fields_->written_at(flow_->time())) write_snapshot();
  if (series_.is_open()) series_.close();
}

void FlowScene::summarise(nlohmann::json& s) {
  const FluidGrid& g = flow_->grid();
  const long cells = long(g.cells()[0]) * g.cells()[1] * g.cells()[2];
  const long steps_run = s["steps_this_run"].get<long>();
  const double volume = liquid_volume();
  nlohmann::json q;
  q["liquid_volume"] = volume;
  q["liquid_volume_drift"] = volume0_ > 0 ? (volume - volume0_) / volume0_ : 0.0;
  q["kinetic_energy"] = flow_->kinetic_energy();
  q["max_speed"] = flow_->max_speed();
  q["peak_speed"] = peak_speed_;
  q["min_liquid_fraction"] = flow_->min_fraction();
  q["max_liquid_fraction"] = flow_->max_fraction();
  q["max_face_divergence"] = flow_->max_face_divergence();
  if (front_along_ >= 0) q["front_position"] = front_position();
  // The volume flux out through each open side (m^3/s; negative: the flow comes in).
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side)
      if (g.boundary(d, side) == BoundaryKind::outflow)
        q["boundary_flux"][std::string(1, char('x' + d)) + (side ? "_high" : "_low")] = flow_->boundary_flux(d, side);

  s["cells"] = cells;
  s["poisson"] = {{"solver", flow_->poisson_description()},
                  {"iterations_per_step", steps_run ? double(poisson_iterations_) / steps_run : 0.0},
                  {"max_iterations", max_iterations_}};
  s["dt_limits"] = limits_;
  s["cell_steps_per_second_per_core"] =
      double(cells) * steps_run / std::max(s["loop_seconds"].get<double>(), 1e-9) / decomp_->size();
  s["quantities"] = q;
  s["output"] = {{"checkpoint", "checkpoint.h5"},
                 {"series", "series.csv"},
                 {"snapshots", fields_->count() ? "fields/fields.xmf" : ""}};
  if (!coupled_) return;
  const DemStats b = dem_->stats();
  const SolidPhaseStats sp = coupled_->solid().stats();
  s["quantities"]["bodies"] = b.bodies;
  s["quantities"]["body_kinetic_energy"] = b.kinetic_translational + b.kinetic_rotational;
  s["quantities"]["body_max_speed"] = b.max_speed;
  s["quantities"]["solid_volume"] = sp.solid_volume;
  s["quantities"]["body_volume"] = sp.body_volume;
  s["quantities"]["solid_volume_error"] = sp.body_volume > 0 ? (sp.solid_volume - sp.body_volume) / sp.body_volume : 0.0;
  s["quantities"]["max_solid_fraction"] = sp.max_fraction;
  if (coupled_->loads_computed()) {  // the fluid's force and moment on all bodies together (C3)
    coupled_->average_held_loads();
    const ParticleStore& p = dem_->particles();
    std::array<ExactSum, 6> sums;
    for (std::size_t i = 0; i < p.owned; ++i)
      for (int k = 0; k < 3; ++k) sums[k].add(p.f_ext[3 * i + k]), sums[3 + k].add(p.t_ext[3 * i + k]);
    ExactSum::all_reduce(sums, decomp_->comm());
    s["quantities"]["fluid_force_on_bodies"] = {sums[0].value(), sums[1].value(), sums[2].value()};
    s["quantities"]["fluid_torque_on_bodies"] = {sums[3].value(), sums[4].value(), sums[5].value()};
  }
  if (coupled_->liquid_in_pores()) {
    const double free = free_liquid_volume();
    s["quantities"]["free_liquid_volume"] = free;
    s["quantities"]["free_liquid_volume_drift"] = free_liquid0_ > 0 ? (free - free_liquid0_) / free_liquid0_ : 0.0;
    s["quantities"]["liquid_in_bodies"] = volume - free;
    s["quantities"]["pore_liquid_max_passes"] = pore_passes_max_;
    s["quantities"]["pore_liquid_max_residual"] = pore_residual_max_;
  }
  long layouts = coupled_->solid().layouts_computed();  // bodies laid out again (C1), all ranks
  MPI_Allreduce(MPI_IN_PLACE, &layouts, 1, MPI_LONG, MPI_SUM, decomp_->comm());
  s["coupling"] = {{"dem_stable_dt", coupled_->dem_stable_dt()},
                   {"layouts", layouts},
                   {"substeps_per_flow_step", steps_run ? double(substeps_total_) / steps_run : 0.0},
                   {"fluid_force", coupling_.fluid_force},
                   {"bodies", coupling_.fixed_bodies ? "fixed" : "moving"}};
  // The leak number dt nu / h^2 (liquid, smallest cell side) over this run's steps: how much flow the
  // partly covered cells let through scales with it (docs/validation.md, the packed bed).
  if (steps_run > 0) {
    const double nu = flow_->settings().liquid.viscosity / flow_->settings().liquid.density;
    const double h = std::min({g.h(0), g.h(1), g.h(2)});
    s["coupling"]["leak_number"] = {step_range_[0] * nu / (h * h), step_range_[1] * nu / (h * h)};
  }
  if (rest_.enabled()) rest_.report(s["quantities"], flow_->time());
  if (drop_) drop_->report(s["quantities"]);
  if (crater_) crater_->finish(*dem_, s["quantities"]);
  if (!bodies_file_.empty()) s["bodies_file"] = fs::absolute(bodies_file_).string();
  s["output"]["checkpoint_bodies"] = "checkpoint_bodies.h5";
  s["output"]["scene"] = fields_->count() ? "scene.xmf" : "";
  s["output"]["bodies"] = bodies_out_->count() ? "snapshots/particles.xmf" : "";
  // The solvers' own phases inside the coupled stages.
  coupled_->timers().merge(flow_->timers(), "flow/");
  coupled_->timers().merge(dem_->timers(), "dem/");
}

}  // namespace

std::unique_ptr<Scene> make_flow_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir, bool coupled) {
  return std::make_unique<FlowScene>(root, comm, dir, coupled);
}

#endif

}  // namespace tessera
