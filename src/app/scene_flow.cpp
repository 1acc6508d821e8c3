// SPDX-License-Identifier: MIT
// The flow scene: air and water in a box (issue 4). Dam breaks, drops into pools and onto floors.
// Case sections: domain, fluid, initial, monitors, run, output (README, section Flow).
//
// `scene: coupled` is the same scene with bodies in the flow (issue 15, src/coupling): their part
// (app/scene_bodies.hpp) makes each step a CoupledSolver::step and adds DIR/snapshots (bodies, grain
// surfaces), the solid fraction with the fields, DIR/scene.xmf (fields and bodies in one time series,
// ParaView) and DIR/checkpoint_bodies.h5 beside DIR/checkpoint.h5. With sections drop and crater it is
// the drop-impact scene (app/drop_impact.hpp): the drop placed over the bed, the crater measured at
// every snapshot and at the end; with bodies.settled_kinetic_energy the run ends once the bodies are
// at rest.
//
// With a `balance` section the cut planes move with the ranks' work (issue 19; docs/design.md, "Load
// balance in a flow or coupled run"): the grid, its fields and the bodies follow.
//
// Writes DIR/summary.json (quantities, timers, Poisson statistics, dt limits), DIR/series.csv
// (one row per series_interval: time, dt and its limit, Poisson iterations and residual, liquid
// volume, kinetic energy, maximum speed, front position), DIR/fields/fields.xmf (ParaView) and
// DIR/checkpoint.h5 (restart with --restart, also written on SIGTERM / SIGUSR1).
#include <algorithm>
#include <cmath>
#include <optional>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include "app/balance_record.hpp"
#include "app/run_loop.hpp"
#include "app/scenes.hpp"
#include "core/balance.hpp"
#include "core/errors.hpp"

#if defined(TESSERA_HAVE_PETSC)
#include "app/scene_bodies.hpp"
#include "fluid/flow_solver.hpp"
#include "fluid/fluid_io.hpp"
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
  // True when the whole cell [lo, hi] lies inside (both kinds are convex: the eight corners
  // decide; an ellipsoid's corners within 1e-9 of its surface count as outside, so that no sample
  // point between them can round to outside).
  bool contains_cell(const Vec3& lo, const Vec3& hi) const {
    if (kind == Kind::box) return lo.x >= a.x && hi.x <= b.x && lo.y >= a.y && hi.y <= b.y && lo.z >= a.z && hi.z <= b.z;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p{corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z};
      const Vec3 q{(p.x - a.x) / b.x, (p.y - a.y) / b.y, (p.z - a.z) / b.z};
      if (!(dot(q, q) <= 1 - 1e-9)) return false;
    }
    return true;
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

class FlowScene final : public SteppedScene {
 public:
  FlowScene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir, bool coupled) {
    const DomainSpec domain = read_domain(root);
    decomp_ = std::make_unique<Decomposition>(comm, domain.lo, domain.hi, domain.grid, domain.cuts);
    const FlowSettings settings = FlowSettings::from_config(root.section("fluid"));
    // Where the case sets no cuts: equal slabs of whole cells in blocks the multigrid halves evenly
    // (cell_block_cuts: no slab larger than equal slabs make it; fewer odd cells, fewer iterations).
    Decomposition::Cuts cuts = decomp_->interior_cuts();
    for (int d = 0; d < 3; ++d)
      if (domain.cuts[d].empty() && decomp_->dims()[d] > 1)
        cuts[d] = flow_default_cuts(domain.lo[d], domain.hi[d], settings.cells[d], decomp_->dims()[d]);
    decomp_->set_cuts(cuts);
    flow_ = std::make_unique<FlowSolver>(*decomp_, settings);
    if (coupled) bodies_ = std::make_unique<SceneBodies>(root, case_dir, *decomp_, *flow_);

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
    balance_.read(root);
    if (balance_.enabled) {
      const ConfigNode b = root.section("balance");
      cell_weight_ = b.real("cell_weight", Dim::none, Range::positive(), cell_weight_);
      if (bodies_ && bodies_->bodies_fixed())
        b.fail("enabled", "false with coupling.bodies: fixed (held bodies' loads are summed per rank between "
                          "snapshots; their work does not move: set domain.cuts instead)");
    }
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

  const char* name() const override { return bodies_ ? "coupled" : "flow"; }

 private:
  void set_initial_state();
  double front_position() const;
  [[noreturn]] void fail(const RunOptions& opt, const std::string& why);
  // Load balance (issue 19, case section `balance`, app/balance_record.hpp).
  WorkBox owned_cells() const;                // this rank's cells, weighing cell_weight_ each
  std::vector<WorkSample> body_work() const;  // SceneBodies::work, none in the flow scene
  double rank_work(double cells_weight, const std::vector<WorkSample>& bodies) const;
  void balance_if_due(const RunOptions& opt);
  void repartition(const CutPlanes& cuts, const RunOptions& opt);
  bool same_grid_of_slabs(const CutPlanes& cuts) const {  // as many cuts per direction as this run has
    for (int d = 0; d < 3; ++d)
      if (int(cuts[d].size()) != decomp_->dims()[d] - 1) return false;
    return true;
  }

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
    const Decomposition::Cuts cuts = decomp_->interior_cuts();
    write_flow_checkpoint(path, *flow_, bodies_ ? bodies_->checkpoint_fields() : std::vector<NamedCellField>{}, &cuts);
    if (bodies_) bodies_->write_checkpoint(path);
  }
  std::string progress() override;
  void end_output(const RunOptions& opt) override;
  void summarise(nlohmann::json& s) override;
  PhaseTimers& phase_timers() override { return bodies_ ? bodies_->timers() : flow_->timers(); }

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
  // The coupled scene's bodies (null in the flow scene).
  std::unique_ptr<SceneBodies> bodies_;
  std::optional<Vec3> drop_centre_;  // the drop placed over the bed by this run
  double liquid_volume() const { return bodies_ ? bodies_->liquid_volume() : flow_->liquid_volume(); }
  bool resuming_ = false;  // the first snapshot of a restarted run
  // The work of a rank: its flow cells, each `cell_weight_` (counts) or the flow's busy seconds
  // (time), and with bodies SceneBodies::work. Counts: a flow cell against a DEM contact-list entry
  // of one sub-step.
  BalanceRecord balance_;
  double cell_weight_ = 1;
};

void FlowScene::set_initial_state() {
  const FluidGrid& g = flow_->grid();
  const FlowSettings& st = flow_->settings();
  std::vector<const LiquidShape*> near;
  flow_->initialize([&](int i, int j, int k) {
    const Vec3 lo{g.lo().x + i * g.h(0), g.lo().y + j * g.h(1), g.lo().z + k * g.h(2)};
    const Vec3 hi{lo.x + g.h(0), lo.y + g.h(1), lo.z + g.h(2)};
    // Only shapes whose bounding box meets the cell are sampled.
    near.clear();
    for (const auto& s : shapes_) {
      const Vec3 a = s.box_min(), b = s.box_max();
      if (a.x < hi.x && b.x > lo.x && a.y < hi.y && b.y > lo.y && a.z < hi.z && b.z > lo.z) near.push_back(&s);
    }
    FlowSolver::CellState cs;
    if (near.empty()) return cs;
    const int m = samples_;
    int count = 0;
    Vec3 momentum;
    if (near.front()->contains_cell(lo, hi)) {
      // Every sample point lies in the first shape: what the loop below would count.
      count = m * m * m;
      momentum = near.front()->velocity * double(count);
    } else {
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
  if (opt.restart) {
    // A balanced run resumes on the cuts it had moved to (the same bits as going on).
    if (balance_.enabled)
      if (const auto cuts = read_checkpoint_cuts(*opt.restart, decomp_->comm()))
        if (same_grid_of_slabs(*cuts) && *cuts != decomp_->interior_cuts()) {
          decomp_->set_cuts(*cuts);
          flow_->repartition(*decomp_);
        }
    read_flow_checkpoint(*opt.restart, *flow_);
  }
  if (!bodies_) return;
  if (const auto d = bodies_->start(opt.restart)) {
    LiquidShape s;
    s.kind = LiquidShape::Kind::ellipsoid;
    s.a = d->centre, s.b = d->semi_axes, s.velocity = d->velocity;
    shapes_.push_back(s);
    drop_centre_ = d->centre;
  }
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
  if (bodies_) bodies_->begin(opt.restart, opt.output_dir);
  volume0_ = liquid_volume();
  peak_speed_ = flow_->max_speed();
  if (!opt.quiet) {
    if (root) {
      const auto& d = decomp_->dims();
      std::printf("tessera %s: scene %s, %d x %d x %d cells, %d ranks (grid %dx%dx%d), Poisson %s\n", kTesseraVersion,
                  name(), g.cells()[0], g.cells()[1], g.cells()[2], decomp_->size(), d[0], d[1], d[2],
                  flow_->poisson_description().c_str());
    }
    if (bodies_) bodies_->print_start(drop_centre_);  // collective
    if (root && !deprecated_.empty()) std::printf("  warning: %s\n", deprecated_.c_str());
    if (root) std::fflush(stdout);
  }
  const bool budget = flow_->settings().energy_budget;
  if (root) {
    const bool append = opt.restart.has_value() && fs::exists(opt.output_dir + "/series.csv");
    series_.open(opt.output_dir + "/series.csv", append ? std::ios::app : std::ios::trunc);
    if (!append)
      series_ << "time,dt,dt_limit,poisson_iterations,poisson_residual,liquid_volume,kinetic_energy,max_speed,"
                 "front_position"
              << (bodies_ ? bodies_->series_header() : "")
              << (budget ? ",potential_energy,energy_advection,energy_viscous,energy_projection" : "") << "\n";
    series_.precision(10);
  }
  fields_ = std::make_unique<FieldSeries>(opt.output_dir + "/fields");
  if (bodies_) bodies_->add_fields(*fields_);
  if (budget) fields_->add_field("advection_energy_source", &flow_->advection_energy_source());
  if (snapshot_interval_ > 0) {
    resuming_ = opt.restart.has_value();  // the crater at this time is the stopped run's last row
    write_snapshot();
    resuming_ = false;
  } else if (bodies_ && !opt.restart) {
    bodies_->sample_crater();  // the bed before the drop
  }
  next_series_ = flow_->time();
}

void FlowScene::write_snapshot() {
  fields_->write(*flow_);
  if (bodies_) bodies_->snapshot(*fields_, resuming_);
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
    last_ = bodies_ ? bodies_->step(dt).flow : flow_->advance(dt);
  } catch (const CollectiveRunError& e) {
    fail(opt, e.what());
  }
  last_limit_ = limit;
  ++limits_[limit];
  poisson_iterations_ += last_.poisson.iterations;
  max_iterations_ = std::max<long>(max_iterations_, last_.poisson.iterations);
  balance_if_due(opt);
}

WorkBox FlowScene::owned_cells() const {
  const FluidGrid& g = flow_->grid();
  WorkBox box;
  long cells = 1;
  for (int d = 0; d < 3; ++d) {
    box.lo[d] = g.lo()[d] + g.begin(d) * g.h(d);
    box.hi[d] = g.lo()[d] + g.end(d) * g.h(d);
    cells *= g.end(d) - g.begin(d);
  }
  box.weight = double(cells) * cell_weight_;
  return box;
}

std::vector<WorkSample> FlowScene::body_work() const {
  return bodies_ ? bodies_->work() : std::vector<WorkSample>{};
}

double FlowScene::rank_work(double cells_weight, const std::vector<WorkSample>& bodies) const {
  double w = cells_weight;
  for (const auto& s : bodies) w += s.weight;
  return w;
}

// Every balance.interval steps: the ranks' work in the step's two stages (their flow cells, their
// bodies), each stage waiting for its busiest rank; above the threshold (the staged imbalance) the
// cut planes move to those of staged_cuts' candidates that make the stages' busiest ranks' sum
// least, on cell faces (or equal slabs, as an unbalanced run has them: a rank owns the cells whose
// centres its slab holds), each slab at least two cells (the halo) and the DEM's contact reach wide.
void FlowScene::balance_if_due(const RunOptions& opt) {
  if (!balance_.due(flow_->steps(), decomp_->size())) return;
  MPI_Comm comm = decomp_->comm();
  WorkBox cells = owned_cells();
  std::vector<WorkSample> bodies = body_work();
  if (balance_.measure_time) {
    // Busy seconds since the last check, the ghost exchanges' waits left out: the flow's over the
    // cells, the bodies' stages over the bodies by their counts.
    PhaseTimers& t = flow_->timers();
    double flow = -t.total("halo_exchange_fields") - t.total("halo_exchange_multigrid");
    for (const char* phase : {"advection", "poisson", "projection", "viscous"}) flow += t.total(phase);
    cells.weight = balance_.busy_since(flow, 0);
    if (bodies_) {
      const double since = balance_.busy_since(bodies_->busy_seconds(), 1), counts = rank_work(0, bodies);
      for (auto& s : bodies) s.weight *= counts > 0 ? since / counts : 0.0;
    }
  }
  const double before = staged_imbalance(comm, {cells.weight, rank_work(0, bodies)});
  if (!balance_.over_threshold(before)) return;
  const FluidGrid& g = flow_->grid();
  const Vec3 lo = decomp_->global_lo(), hi = decomp_->global_hi();
  Vec3 min_width, spacing;
  for (int d = 0; d < 3; ++d) {
    spacing[d] = g.h(d);
    min_width[d] = FluidGrid::kGhost * g.h(d);
    if (bodies_) min_width[d] = std::max(min_width[d], bodies_->contact_reach() + g.h(d));
    if (decomp_->dims()[d] * min_width[d] >= hi[d] - lo[d]) return;  // no room to move the cuts
  }
  // The flow's stage and the bodies' each wait for their busiest rank (staged_cuts).
  const CutPlanes now = decomp_->interior_cuts();
  CutPlanes cuts =
      staged_cuts(comm, {{{}, {cells}}, {bodies, {}}}, lo, hi, decomp_->dims(), min_width, spacing, 4096, &now).cuts;
  for (auto& c : cuts) MPI_Bcast(c.data(), static_cast<int>(c.size()), MPI_DOUBLE, 0, comm);  // one rounding
  if (cuts == decomp_->interior_cuts()) return;  // already where the work puts them (to a cell)
  repartition(cuts, opt);
  std::optional<double> after;
  if (!balance_.measure_time)
    after = staged_imbalance(comm, {owned_cells().weight, rank_work(0, body_work())});
  balance_.rebalanced(flow_->steps(), before, after);
}

// The state moves to the new cuts through a flow checkpoint (the restart's path, bit for bit: the
// fields by global index, parallel HDF5): written on the old grid, read on the new one; the bodies
// move in memory (DemSolver::rebalance) and the coupling is made again on the new grid as at a
// restart. The file, DIR/repartition.h5, is removed after.
void FlowScene::repartition(const CutPlanes& cuts, const RunOptions& opt) {
  const std::string path = opt.output_dir + "/repartition.h5";
  write_flow_checkpoint(path, *flow_, bodies_ ? bodies_->checkpoint_fields() : std::vector<NamedCellField>{});
  decomp_->set_cuts(cuts);
  flow_->repartition(*decomp_);
  read_flow_checkpoint(path, *flow_);
  if (bodies_) {
    bodies_->repartition(path);
    bodies_->add_fields(*fields_);
  }
  MPI_Barrier(decomp_->comm());
  if (decomp_->rank() == 0) fs::remove(path);
}

bool FlowScene::after_step(const RunOptions& opt) {
  const bool at_rest = bodies_ && bodies_->check([&](const std::string& why) { fail(opt, why); });
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
    std::string tail;  // the bodies' columns, then the energy budget's
    if (bodies_) tail = bodies_->series_row();
    if (flow_->settings().energy_budget) {
      const double potential = flow_->potential_energy();
      const auto& b = flow_->energy_budget();
      std::ostringstream row;
      row.precision(10);
      row << ',' << potential << ',' << b.advection << ',' << b.viscous << ',' << b.projection;
      tail += row.str();
    }
    if (flow_->grid().rank() == 0)
      series_ << flow_->time() << ',' << last_.dt << ',' << last_limit_ << ',' << last_.poisson.iterations << ','
              << last_.poisson.residual << ',' << volume << ',' << ke << ',' << vmax << ',' << front << tail
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
  return bodies_ ? line + bodies_->progress() : line;
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
  if (flow_->settings().energy_budget) {
    const auto& b = flow_->energy_budget();
    q["potential_energy"] = flow_->potential_energy();
    q["energy_budget"] = {{"advection", b.advection}, {"viscous", b.viscous}, {"projection", b.projection}};
  }
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
                  {"max_iterations", max_iterations_},
                  {"coarsest_cells", flow_->poisson_coarsest_cells()},
                  {"levels", flow_->poisson_levels()},
                  {"gathered_levels", flow_->poisson_gathered_levels()},
                  {"two_layer_levels", flow_->poisson_two_layer_levels()},
                  {"exchanges_per_cycle", flow_->poisson_exchanges_per_cycle()},
                  {"reductions_per_iteration", flow_->settings().poisson.single_reduction ? 2 : 3}};
  s["dt_limits"] = limits_;
  s["cell_steps_per_second_per_core"] =
      double(cells) * steps_run / std::max(s["loop_seconds"].get<double>(), 1e-9) / decomp_->size();
  s["quantities"] = q;
  // The ranks' work by counts (flow cells times balance.cell_weight, the bodies' DemSolver::work per
  // flow step) and the balance's record.
  {
    const WorkBox box = owned_cells();
    const double owned = double(std::lround(box.weight / cell_weight_));  // the cell count
    const double body_weight = rank_work(0, body_work()), local = box.weight + body_weight;
    s["imbalance"] = staged_imbalance(decomp_->comm(), {box.weight, body_weight});  // the two stages'
    const int size = decomp_->size();
    // And what each rank's ghost exchanges sent over the run: the flow's fields and multigrid
    // (messages, bytes), the bodies' (bytes).
    const CellHalo::Traffic fields = flow_->field_traffic(), multigrid = flow_->multigrid_traffic();
    constexpr int n = 10;
    const double mine[n] = {double(owned),
                            local,
                            double(fields.messages),
                            fields.bytes,
                            double(multigrid.messages),
                            multigrid.bytes,
                            bodies_ ? double(bodies_->halo_bytes_sent()) : 0.0,
                            bodies_ ? double(bodies_->listed_elements()) : 0.0,
                            bodies_ ? double(bodies_->ghost_elements_left_out()) : 0.0,
                            bodies_ ? double(bodies_->list_tests()) : 0.0};
    std::vector<double> all(n * std::size_t(size));
    MPI_Allgather(mine, n, MPI_DOUBLE, all.data(), n, MPI_DOUBLE, decomp_->comm());
    const char* names[n] = {"cells", "work", "field_halo_messages", "field_halo_bytes", "multigrid_halo_messages",
                            "multigrid_halo_bytes", "body_halo_bytes", "listed_elements", "ghost_elements_left_out",
                            "neighbor_list_tests"};
    nlohmann::json per_rank;
    for (int k = 0; k < n; ++k) {
      if (k >= 6 && !bodies_) break;  // the bodies' halo and list (T5b: the last binning's; T5c: its work)
      per_rank[names[k]] = nlohmann::json::array();
      for (int r = 0; r < size; ++r) {
        const double v = all[std::size_t(n * r + k)];
        if (k == 1)
          per_rank[names[k]].push_back(v);
        else
          per_rank[names[k]].push_back(long(v));
      }
    }
    s["per_rank"] = per_rank;
    if (balance_.enabled) {
      s["balance"] = balance_.summary();
      s["balance"]["cell_weight"] = cell_weight_;
    }
  }
  s["output"] = {{"checkpoint", "checkpoint.h5"},
                 {"series", "series.csv"},
                 {"snapshots", fields_->count() ? "fields/fields.xmf" : ""}};
  if (bodies_) bodies_->summarise(s, steps_run, volume, *fields_);
}

}  // namespace

std::unique_ptr<Scene> make_flow_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir, bool coupled) {
  return std::make_unique<FlowScene>(root, comm, dir, coupled);
}

#endif

}  // namespace tessera
