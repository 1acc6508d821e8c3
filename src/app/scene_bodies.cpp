// SPDX-License-Identifier: MIT
#include "app/scene_bodies.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <sstream>

#include "core/errors.hpp"
#include "core/exact_sum.hpp"
#include "core/text_file.hpp"
#include "solid/shape.hpp"

namespace tessera {

namespace fs = std::filesystem;

namespace {

// The bodies' checkpoint beside the flow's: DIR/checkpoint.h5 -> DIR/checkpoint_bodies.h5.
std::string bodies_path(const std::string& flow_checkpoint) {
  const fs::path p(flow_checkpoint);
  return (p.parent_path() / (p.stem().string() + "_bodies" + p.extension().string())).string();
}

}  // namespace

SceneBodies::SceneBodies(const ConfigNode& root, const std::string& case_dir, const Decomposition& decomp,
                         FlowSolver& flow)
    : decomp_(decomp), flow_(flow) {
  const ConfigNode solid = root.section("solid");
  ContactModel model(solid);
  Walls walls(solid, model, case_dir);
  const DemSettings ds = DemSettings::from_config(solid);
  const Vec3 gf = flow_.settings().gravity;
  if (norm(ds.gravity - gf) > 1e-12 * (norm(gf) + 1))
    solid.fail("gravity", "the fluid's gravity (the same field acts on fluid and bodies)");
  dem_ = std::make_unique<DemSolver>(decomp_, std::move(model), std::move(walls), ds);
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
    for (const ConfigNode& e : b.list("list")) {
      BodySpec s;
      const std::string shape = e.text("shape");
      s.shape = 0;
      for (std::size_t k = 0; k < dem_->shapes().size(); ++k)
        if (dem_->shapes()[k].name == shape) s.shape = int(k) + 1;
      if (!s.shape) e.fail("shape", "the name of a template in solid.shapes");
      s.material = dem_->model().material_index(e.text("material"), e.key_path("material"));
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
      s.density = e.real("density", Dim::density, Range::non_negative(), 0.0);  // 0: the material's
      body_list_.push_back(s);
    }
    if (body_list_.empty()) b.fail("list", "at least one body");
  }
  rest_ = SettleCriterion(b, false);
  const Vec3 lo = decomp_.global_lo(), hi = decomp_.global_hi();
  if (const auto d = root.optional_section("drop")) drop_.emplace(*d, lo, hi, flow_.settings().liquid.density);
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

void SceneBodies::create_bodies() {
  if (!bodies_file_.empty()) {
    read_checkpoint(bodies_file_, *dem_);
    dem_->set_clock(0.0, 0);
    dem_->setup(false);
  } else {
    std::int64_t id = 0;
    for (const BodySpec& b : body_list_) dem_->add_body(id++, b.material, b.shape, b.x, b.q, b.v, b.omega, b.density);
    dem_->setup(true);
  }
  // A body outside the box (a bed made in a taller box, a grain still in flight above this lid) is
  // refused here: the flow cannot hold it, and its first step would fail far from the cause.
  if (const auto out = body_outside()) {
    std::ostringstream m;
    m << "body " << out->first << " at (" << out->second.x << ", " << out->second.y << ", " << out->second.z
      << ") m lies outside the domain; every body's centre inside the box";
    throw InputError(bodies_file_.empty() ? "bodies.list" : "bodies.file", bodies_file_, m.str());
  }
}

std::optional<std::pair<std::int64_t, Vec3>> SceneBodies::body_outside() const {
  const ParticleStore& p = dem_->particles();
  const Vec3 lo = decomp_.global_lo(), hi = decomp_.global_hi();
  std::int64_t outside = std::numeric_limits<std::int64_t>::max();  // lowest id of a body out of the box
  Vec3 where{};
  for (std::size_t i = 0; i < p.owned; ++i) {
    const Vec3 x = p.pos(i);
    if ((x.x < lo.x || x.x > hi.x || x.y < lo.y || x.y > hi.y || x.z < lo.z || x.z > hi.z) && p.id[i] < outside)
      outside = p.id[i], where = x;
  }
  std::int64_t lowest = outside;
  MPI_Allreduce(MPI_IN_PLACE, &lowest, 1, MPI_INT64_T, MPI_MIN, decomp_.comm());
  if (lowest == std::numeric_limits<std::int64_t>::max()) return std::nullopt;
  double c[3] = {0, 0, 0};  // its centre, from its owner
  if (outside == lowest) c[0] = where.x, c[1] = where.y, c[2] = where.z;
  MPI_Allreduce(MPI_IN_PLACE, c, 3, MPI_DOUBLE, MPI_SUM, decomp_.comm());
  return std::make_pair(lowest, Vec3{c[0], c[1], c[2]});
}

CheckpointExtras SceneBodies::extras() const {
  CheckpointExtras e;
  rest_.save(e);
  if (drop_) drop_->save(e);
  if (crater_) crater_->save(e);
  return e;
}

void SceneBodies::restore_extras(const CheckpointExtras& e) {
  rest_.restore(e);
  if (drop_) drop_->restore(e);
  if (crater_) crater_->restore(e);
}

std::optional<DropShape> SceneBodies::start(const std::optional<std::string>& restart) {
  std::optional<DropShape> drop;
  if (restart) {
    restore_extras(read_checkpoint(bodies_path(*restart), *dem_));
    dem_->setup(false);
  } else {
    create_bodies();
    if (drop_) drop = drop_->place(*dem_);
    if (crater_) crater_->start(*dem_);
  }
  coupled_ = std::make_unique<CoupledSolver>(flow_, *dem_, coupling_);
  if (restart && coupling_.liquid_in_pores)
    read_checkpoint_cell_field(*restart, flow_.grid(), "liquid_content", coupled_->mutable_liquid().mutable_content(),
                               "the liquid in the cells' fluid part, theory C7; coupled checkpoints from 2026-11-29 on");
  return drop;
}

void SceneBodies::begin(const std::optional<std::string>& restart, const std::string& dir) {
  coupled_->start(!restart);  // a restart's velocities were corrected when saved
  if (coupling_.momentum_budget) coupled_->start_momentum_budget();  // from the start or the restart
  if (coupled_->liquid_in_pores()) free_liquid0_ = free_liquid_volume();
  output_dir_ = dir;
  bodies_out_ = std::make_unique<SnapshotSeries>(dir + "/snapshots");
  bodies_out_->write_loads(coupled_->loads_computed());
  if (crater_) crater_->open(dir, restart.has_value() && fs::exists(dir + "/crater.csv"), flow_.grid().rank() == 0);
  checks_ = Schedule(check_interval_, flow_.time(), flow_.last_dt());
}

void SceneBodies::add_fields(FieldSeries& fields) const {
  fields.add_field("solid_fraction", &coupled_->solid().fraction());
  if (coupled_->liquid_in_pores()) fields.add_field("liquid_content", &coupled_->liquid().content());
}

void SceneBodies::sample_crater() {
  if (crater_) crater_->sample(*dem_, flow_.time());
}

void SceneBodies::print_start(const std::optional<Vec3>& drop_centre) const {
  const long bodies = dem_->stats().bodies;  // collective
  if (flow_.grid().rank() != 0) return;
  std::printf("  bodies: %ld, DEM stable step %.4g s, sub-steps %s\n", bodies, coupled_->dem_stable_dt(),
              coupling_.fixed_bodies ? "none (coupling.bodies: fixed)"
              : coupling_.substeps   ? std::to_string(*coupling_.substeps).c_str()
                                     : "from each flow step's dt");
  if (drop_ && drop_centre)
    std::printf("  drop: centre %.4g m above the floor, %.4g m above the bed's top\n", drop_centre->z,
                drop_centre->z - drop_->bed_top_height());
}

CoupledStepStats SceneBodies::step(double dt) {
  const CoupledStepStats cs = coupled_->step(dt);
  last_substeps_ = cs.substeps;
  pore_passes_max_ = std::max(pore_passes_max_, cs.liquid.passes);
  pore_residual_max_ = std::max(pore_residual_max_, cs.liquid.residual);
  substeps_total_ += cs.substeps;
  step_range_[0] = std::min(step_range_[0], dt), step_range_[1] = std::max(step_range_[1], dt);
  return cs;
}

bool SceneBodies::check(const std::function<void(const std::string&)>& fail) {
  if (!checks_.due(flow_.time(), flow_.last_dt())) return false;
  const DemStats s = dem_->stats();
  if (const auto out = body_outside())
    fail("body " + std::to_string(out->first) + " left the box (a wall it passed through, or a blow-up)");
  if (s.finite && s.max_overlap_ratio <= max_overlap_ratio_) return rest_.check(s, flow_.time());
  std::ostringstream m;
  if (!s.finite)
    m << "non-finite body positions or velocities";
  else
    m << "overlap of body " << s.max_overlap_body << " reached " << s.max_overlap_ratio
      << " of its contact radius (run.max_overlap_ratio = " << max_overlap_ratio_
      << "): stiffer contacts, or more DEM sub-steps (coupling.substeps)";
  fail(m.str());
  return false;
}

void SceneBodies::snapshot(const FieldSeries& fields, bool resuming) {
  coupled_->average_held_loads();  // fixed bodies: their loads over the interval
  bodies_out_->write(*dem_);
  write_scene_index(fields);
  if (crater_ && !resuming) crater_->sample(*dem_, flow_.time());
}

// DIR/scene.xmf: per snapshot a spatial collection of the fields and the bodies (and the grains'
// surfaces), at the flow's time.
void SceneBodies::write_scene_index(const FieldSeries& fields) const {
  if (flow_.grid().rank() != 0) return;
  std::ostringstream x;
  x.precision(17);
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n"
    << "<Grid Name=\"scene\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  const std::size_t n = std::min<std::size_t>(std::size_t(fields.count()), bodies_out_->count());
  for (std::size_t k = 0; k < n; ++k) {
    x << "<Grid Name=\"step\" GridType=\"Collection\" CollectionType=\"Spatial\">\n<Time Value=\""
      << fields.time_of(int(k)) << "\"/>\n"
      << fields.grid_xml(flow_.grid(), int(k), "fields/") << bodies_out_->grid_xml(k, "snapshots/", false)
      << bodies_out_->grid_xml(k, "snapshots/", true) << "</Grid>\n";
  }
  x << "</Grid>\n</Domain>\n</Xdmf>\n";
  write_file_atomically(output_dir_ + "/scene.xmf", x.str());
}

void SceneBodies::write_checkpoint(const std::string& flow_checkpoint) const {
  tessera::write_checkpoint(bodies_path(flow_checkpoint), *dem_, extras());
}

void SceneBodies::repartition(const std::string& flow_state) {
  dem_->rebalance();
  auto fresh = std::make_unique<CoupledSolver>(flow_, *dem_, coupling_);
  fresh->take_over(*coupled_);
  coupled_ = std::move(fresh);
  if (coupling_.liquid_in_pores)
    read_checkpoint_cell_field(flow_state, flow_.grid(), "liquid_content", coupled_->mutable_liquid().mutable_content(),
                               "the liquid in the cells' fluid part");
  coupled_->start(false);
}

std::vector<WorkSample> SceneBodies::work() const {
  std::vector<WorkSample> w = dem_->work();
  const double per_step = std::max(1, last_substeps_);
  for (auto& s : w) s.weight *= per_step;
  return w;
}

double SceneBodies::busy_seconds() {
  double busy = 0;
  for (const char* stage : {"dem_substeps", "solid_fraction", "fluid_force", "pore_liquid", "correction"})
    busy += coupled_->timers().total(stage);
  return busy;
}

std::vector<NamedCellField> SceneBodies::checkpoint_fields() const {
  if (!coupled_ || !coupled_->liquid_in_pores()) return {};
  return {{"liquid_content", &coupled_->liquid().content()}};
}

double SceneBodies::liquid_volume() const {
  return coupled_->liquid_in_pores() ? coupled_->liquid().volume() : flow_.liquid_volume();
}

// The part of the liquid within the cells' fluid part (all of it, to the liquid stage's tolerance).
double SceneBodies::free_liquid_volume() const {
  return liquid_volume() - coupled_->liquid().volume_in_bodies(coupled_->solid().fraction());
}

std::string SceneBodies::series_header() const {
  return ",body_kinetic_energy,body_max_speed,body_mean_x,body_mean_y,body_mean_z,body_mean_vx,body_mean_vy,"
         "body_mean_vz,substeps";
}

// The bodies' columns of series.csv: kinetic energy, largest speed, mean position and velocity
// (exact sums: the same on any rank count for the same state), sub-steps of the last step.
std::string SceneBodies::series_row() {
  const DemStats st = dem_->stats();
  const ParticleStore& p = dem_->particles();
  std::array<ExactSum, 6> sums;
  for (std::size_t i = 0; i < p.owned; ++i)
    for (int k = 0; k < 3; ++k) sums[k].add(p.x[3 * i + k]), sums[3 + k].add(p.v[3 * i + k]);
  ExactSum::all_reduce(sums, decomp_.comm());
  std::ostringstream o;
  o.precision(10);
  o << ',' << st.kinetic_translational + st.kinetic_rotational << ',' << st.max_speed;
  for (auto& e : sums) o << ',' << (st.bodies ? e.value() / double(st.bodies) : 0.0);
  o << ',' << last_substeps_;
  return o.str();
}

std::string SceneBodies::progress() {
  const DemStats b = dem_->stats();
  char more[160];
  std::snprintf(more, sizeof more, "  L %d  bodies KE %.3g J  max|v| %.3g m/s", last_substeps_,
                b.kinetic_translational + b.kinetic_rotational, b.max_speed);
  return more;
}

void SceneBodies::summarise(nlohmann::json& s, long steps_run, double volume, const FieldSeries& fields) {
  const FluidGrid& g = flow_.grid();
  const DemStats b = dem_->stats();
  const SolidPhaseStats sp = coupled_->solid().stats();
  nlohmann::json& q = s["quantities"];
  q["bodies"] = b.bodies;
  q["body_kinetic_energy"] = b.kinetic_translational + b.kinetic_rotational;
  q["body_max_speed"] = b.max_speed;
  q["solid_volume"] = sp.solid_volume;
  q["body_volume"] = sp.body_volume;
  q["solid_volume_error"] = sp.body_volume > 0 ? (sp.solid_volume - sp.body_volume) / sp.body_volume : 0.0;
  q["max_solid_fraction"] = sp.max_fraction;
  if (coupled_->loads_computed()) {  // the fluid's force and moment on all bodies together (C3)
    coupled_->average_held_loads();
    const ParticleStore& p = dem_->particles();
    std::array<ExactSum, 6> sums;
    for (std::size_t i = 0; i < p.owned; ++i)
      for (int k = 0; k < 3; ++k) sums[k].add(p.f_ext[3 * i + k]), sums[3 + k].add(p.t_ext[3 * i + k]);
    ExactSum::all_reduce(sums, decomp_.comm());
    q["fluid_force_on_bodies"] = {sums[0].value(), sums[1].value(), sums[2].value()};
    q["fluid_torque_on_bodies"] = {sums[3].value(), sums[4].value(), sums[5].value()};
  }
  if (coupled_->liquid_in_pores()) {
    const double free = free_liquid_volume();
    q["free_liquid_volume"] = free;
    q["free_liquid_volume_drift"] = free_liquid0_ > 0 ? (free - free_liquid0_) / free_liquid0_ : 0.0;
    q["liquid_in_bodies"] = volume - free;
    q["pore_liquid_max_passes"] = pore_passes_max_;
    q["pore_liquid_max_residual"] = pore_residual_max_;
  }
  // Bodies laid out again (C1), all ranks; of them, those whose nodes could not reach the rank's
  // cells (ghosts: skipped).
  long layouts[2] = {coupled_->solid().layouts_computed(), coupled_->solid().layouts_elsewhere()};
  MPI_Allreduce(MPI_IN_PLACE, layouts, 2, MPI_LONG, MPI_SUM, decomp_.comm());
  s["coupling"] = {{"dem_stable_dt", coupled_->dem_stable_dt()},
                   {"layouts", layouts[0]},
                   {"layouts_elsewhere", layouts[1]},
                   {"substeps_per_flow_step", steps_run ? double(substeps_total_) / steps_run : 0.0},
                   {"fluid_force", coupling_.fluid_force},
                   {"bodies", coupling_.fixed_bodies ? "fixed" : "moving"}};
  // The DEM's contact list (as the DEM scenes report it): its builds, and its entries over all ranks.
  s["neighbor_list_builds"] = dem_->list_builds();
  s["neighbor_list_relists"] = dem_->list_relists();
  long listed = static_cast<long>(dem_->pair_count());
  MPI_Allreduce(MPI_IN_PLACE, &listed, 1, MPI_LONG, MPI_SUM, decomp_.comm());
  s["listed_pairs"] = listed;
  // The leak number dt nu / h^2 (liquid, smallest cell side) over this run's steps: how much flow the
  // partly covered cells let through scales with it (docs/validation.md, the packed bed).
  if (steps_run > 0) {
    const double nu = flow_.settings().liquid.viscosity / flow_.settings().liquid.density;
    const double h = std::min({g.h(0), g.h(1), g.h(2)});
    s["coupling"]["leak_number"] = {step_range_[0] * nu / (h * h), step_range_[1] * nu / (h * h)};
  }
  if (coupled_->momentum_budget().started()) {  // C8: what gravity and the walls gave, what each stage left
    const MomentumBudget& mb = coupled_->momentum_budget();
    auto vec = [](const Vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); };
    nlohmann::json stages;
    for (int k = 0; k < MomentumBudget::stages; ++k)
      stages[MomentumBudget::name(MomentumBudget::Stage(k))] = vec(mb.stage_residual(MomentumBudget::Stage(k)));
    s["coupling"]["momentum_budget"] = {{"momentum_start", vec(mb.start_totals().fluid + mb.start_totals().bodies)},
                                        {"momentum_end", vec(mb.now().fluid + mb.now().bodies)},
                                        {"body_momentum_end", vec(mb.now().bodies)},
                                        {"gravity_impulse", vec(mb.gravity_impulse())},
                                        {"fluid_wall_impulse", vec(mb.fluid_wall_impulse())},
                                        {"body_wall_impulse", vec(mb.body_wall_impulse())},
                                        {"residual", vec(mb.residual())},
                                        {"stage_residuals", stages}};
  }
  if (rest_.enabled()) rest_.report(q, flow_.time());
  if (drop_) drop_->report(q);
  if (crater_) crater_->finish(*dem_, q);
  if (!bodies_file_.empty()) s["bodies_file"] = fs::absolute(bodies_file_).string();
  s["output"]["checkpoint_bodies"] = "checkpoint_bodies.h5";
  s["output"]["scene"] = fields.count() ? "scene.xmf" : "";
  s["output"]["bodies"] = bodies_out_->count() ? "snapshots/particles.xmf" : "";
  // The solvers' own phases inside the coupled stages.
  coupled_->timers().merge(flow_.timers(), "flow/");
  coupled_->timers().merge(dem_->timers(), "dem/");
}

}  // namespace tessera
