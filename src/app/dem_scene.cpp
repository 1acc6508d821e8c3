// SPDX-License-Identifier: MIT
#include "app/dem_scene.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "app/signals.hpp"
#include "core/errors.hpp"
#include "core/text_file.hpp"
#include "tessera_version.hpp"

namespace tessera {

namespace fs = std::filesystem;

DemScene::DemScene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir) : case_dir_(case_dir) {
  DomainSpec domain = read_domain(root);
  const ConfigNode solid = root.section("solid");
  if (const auto plane = solid.optional_section("plane")) {
    // Plane mode: one process along the normal (the sub-domains tile the plane).
    const int n = plane->choice("normal", {"x", "y", "z"})[0] - 'x';
    if (domain.grid[n] > 1)
      root.section("domain").fail("process_grid", std::string("1 along the plane's normal (") + "xyz"[n] + ")");
    domain.grid[n] = 1;
  }
  decomp_ = std::make_unique<Decomposition>(comm, domain.lo, domain.hi, domain.grid, domain.cuts);

  ContactModel model(solid);
  Walls walls(solid, model, case_dir);
  dem_ = std::make_unique<DemSolver>(*decomp_, std::move(model), std::move(walls), DemSettings::from_config(solid));
  dem_->set_shapes(read_shapes(solid, case_dir));
  // Free spheres (T17): bodies far larger than the grains (the bunker shot's ball), on every rank.
  for (const auto& b : solid.list("free_spheres")) {
    const int mat = dem_->model().material_index(b.text("material"), b.key_path("material"));
    dem_->add_free_sphere(b.text("key", b.path()), mat, 0.5 * b.real("diameter", Dim::length, Range::positive()),
                          b.vec3("position", Dim::length), b.vec3("velocity", Dim::velocity, Vec3{}),
                          b.vec3("angular_velocity", Dim::angular_velocity, Vec3{}),
                          b.real("density", Dim::density, Range::non_negative(), 0.0));  // 0: the material's
  }

  read_loop_keys(root, false);
  const ConfigNode run = root.section("run");
  check_interval_ = run.real("check_interval", Dim::time, Range::positive(), 1e-3);
  max_overlap_ratio_ = run.real("max_overlap_ratio", Dim::none, Range{0.0, 2.0, true, false}, max_overlap_ratio_);
  poll_every_ = 100;
  balance_.read(root);
}

void DemScene::balance_if_due() {
  if (!balance_.due(dem_->steps(), decomp_->size())) return;
  MPI_Comm comm = decomp_->comm();
  auto local_work = [](const std::vector<WorkSample>& w) {
    double sum = 0;
    for (const auto& s : w) sum += s.weight;
    return sum;
  };
  std::vector<WorkSample> work = dem_->work();
  if (balance_.measure_time) {
    // The rank's busy seconds since the last check (not its waits), over its bodies by their counts.
    double busy = 0;
    for (const char* phase : {"integrate", "neighbor", "migration", "ghost_comm", "contact_forces", "wall_forces"})
      busy += dem_->timers().total(phase);
    const double since = balance_.busy_since(busy), counts = local_work(work);
    for (auto& w : work) w.weight *= counts > 0 ? since / counts : 0.0;
  }
  const double before = imbalance(comm, local_work(work));
  if (!balance_.over_threshold(before)) return;
  // Slabs stay wider than the contact reach (DemSolver's check is strict), by a bin of the search.
  const Vec3 lo = decomp_->global_lo(), hi = decomp_->global_hi();
  Vec3 min_width;
  for (int d = 0; d < 3; ++d) min_width[d] = dem_->contact_reach() + 2 * (hi[d] - lo[d]) / 4096;
  for (int d = 0; d < 3; ++d)
    if (decomp_->dims()[d] * min_width[d] >= hi[d] - lo[d]) return;  // no room to move the cuts
  CutPlanes cuts = balanced_cuts(comm, work, lo, hi, decomp_->dims(), min_width);
  if (balance_.measure_time)  // sums of measured seconds: rank 0's cuts for all, whatever the rounding
    for (auto& c : cuts) MPI_Bcast(c.data(), static_cast<int>(c.size()), MPI_DOUBLE, 0, comm);
  decomp_->set_cuts(cuts);
  dem_->rebalance();
  // Counts: the new cuts' imbalance now; time: known at the next check (its `before`).
  std::optional<double> after;
  if (!balance_.measure_time) after = imbalance(comm, local_work(dem_->work()));
  balance_.rebalanced(dem_->steps(), before, after);
}

std::string DemScene::resolve_path(const std::string& p) const {
  const fs::path path(p);
  return path.is_absolute() ? p : (fs::path(case_dir_) / path).lexically_normal().string();
}

void DemScene::require_pairs(const std::vector<int>& mats) const {
  const ContactModel& model = dem_->model();
  for (int a : mats)
    for (int b : mats)
      if (!model.has_pair(a, b))
        throw InputError(
            "solid.contact.pairs", "",
            "needs an entry for materials [" + model.materials()[a].name + ", " + model.materials()[b].name + "]");
  dem_->walls().check_pairs(model, mats);
}

void DemScene::check_health(const DemStats& s, const RunOptions& opt) {
  if (s.finite && s.max_overlap_ratio <= max_overlap_ratio_) return;
  tessera::write_checkpoint(opt.output_dir + "/failure.h5", *dem_, extras());
  std::ostringstream m;
  m << "blow-up at step " << dem_->steps() << ", t = " << dem_->time() << " s: ";
  if (!s.finite)
    m << "non-finite body positions or velocities";
  else
    m << "overlap of body " << s.max_overlap_body << " reached " << s.max_overlap_ratio
      << " of its radius (run.max_overlap_ratio = " << max_overlap_ratio_ << ")";
  m << ". The contacts are too soft for the impact speeds, or the time step (" << dem_->dt()
    << " s) is too large for the contact duration (" << dem_->contact_duration()
    << " s): stiffen the contacts or raise solid.steps_per_contact. Failing state: " << opt.output_dir
    << "/failure.h5; last good state: the latest " << opt.output_dir << "/checkpoint.h5, if any.";
  throw CollectiveRunError(m.str());
}

void DemScene::start(const RunOptions& opt) {
  if (opt.restart) {
    restore(read_checkpoint(*opt.restart, *dem_));
    dem_->setup(false);
  } else {
    create_bodies();
    dem_->setup(!continues_state());
  }
}

void DemScene::begin_output(const RunOptions& opt) {
  const DemStats stats = dem_->stats();
  if (decomp_->rank() == 0 && !opt.quiet) {
    const auto& g = decomp_->dims();
    std::printf("tessera %s: scene %s, %ld bodies, %d ranks (grid %dx%dx%d), law %s\n", kTesseraVersion, name(),
                stats.bodies, decomp_->size(), g[0], g[1], g[2], dem_->model().law_name());
    std::printf("  dt %.4g s (contact duration %.4g s), skin %.4g m\n", dem_->dt(), dem_->contact_duration(),
                dem_->skin());
    if (dem_->dt() > 0.1 * dem_->contact_duration())
      std::printf("  warning: dt is %.2g of the contact duration; contacts are resolved with fewer than 10 steps\n",
                  dem_->dt() / dem_->contact_duration());
    std::fflush(stdout);
  }
  snapshots_ = std::make_unique<SnapshotSeries>(opt.output_dir + "/snapshots");
  if (snapshot_interval_ > 0) snapshots_->write(*dem_);
  checks_ = Schedule(check_interval_, dem_->time(), dem_->steps() > 0 ? dem_->dt() : 0.0);
}

void DemScene::step(const RunOptions& opt) {
  // The second half-kick of the bodies waits for the next step's first pass (one sweep over the
  // bodies instead of two); anything that reads body state completes the step first.
  dem_->step(true);
  on_step(opt);
}

bool DemScene::after_step(const RunOptions& opt) {
  balance_if_due();
  if (!checks_.due(dem_->time(), dem_->dt())) return false;
  dem_->complete_step();
  const DemStats stats = dem_->stats();
  cross_rank_contacts_ += stats.cross_rank_contacts;
  check_health(stats, opt);
  return finished(stats);
}

void DemScene::write_snapshot() { snapshots_->write(*dem_); }

void DemScene::write_checkpoint(const std::string& path) { tessera::write_checkpoint(path, *dem_, extras()); }

std::string DemScene::progress() {
  dem_->complete_kick();  // not complete_step: progress comes at wall-clock moments (see there)
  const DemStats stats = dem_->stats();
  char line[160];
  std::snprintf(line, sizeof line, "KE %.3g J  Z %.2f  max|v| %.3g m/s",
                stats.kinetic_translational + stats.kinetic_rotational,
                stats.bodies ? 2.0 * stats.body_contacts / stats.bodies : 0.0, stats.max_speed);
  return line;
}

void DemScene::end_output(const RunOptions& opt) {
  dem_->complete_step();
  write_checkpoint(opt.output_dir + "/checkpoint.h5");
  if (snapshot_interval_ > 0) snapshots_->write(*dem_);
  finish(opt);
}

void DemScene::summarise(nlohmann::json& s) {
  MPI_Comm comm = decomp_->comm();
  const DemStats stats = dem_->stats();
  nlohmann::json q;
  q["bodies"] = stats.bodies;
  q["kinetic_energy"] = stats.kinetic_translational + stats.kinetic_rotational;
  q["coordination_number"] = stats.bodies ? 2.0 * stats.body_contacts / stats.bodies : 0.0;
  if (dem_->shaped()) q["touching_contact_sphere_pairs"] = stats.contacts;
  quantities(q);

  s["dt"] = dem_->dt();
  s["contact_law"] = dem_->model().law_name();
  s["neighbor_list_builds"] = dem_->list_builds();
  s["neighbor_list_relists"] = dem_->list_relists();
  long counts[3] = {static_cast<long>(dem_->pair_count()), static_cast<long>(dem_->halo_bytes_sent()),
                    static_cast<long>(dem_->migrations())};
  MPI_Allreduce(MPI_IN_PLACE, counts, 3, MPI_LONG, MPI_SUM, comm);
  s["listed_pairs"] = counts[0];     // contact-list entries over all ranks at the end
  s["halo_bytes_sent"] = counts[1];  // ghost and migration traffic, all ranks, this run
  s["migrations"] = counts[2];       // bodies that changed owner, this run
  // Touching pairs whose bodies have different owners, summed over the run.check_interval checks.
  s["cross_rank_contacts_checked"] = cross_rank_contacts_;
  // The ranks' work (DemSolver::work: bodies and their listed contacts) at the end, and what the
  // balance did.
  {
    double local = 0;
    for (const auto& w : dem_->work()) local += w.weight;
    s["imbalance"] = imbalance(comm, local);  // the final cut planes: "cuts" (run_loop.cpp)
    // Per rank, in rank order (the timers' per_rank beside them): bodies, work, halo bytes sent,
    // the list's relists (T5a: all ranks relist together, so these are equal), at the last
    // binning the elements in the list's cells and the ghosts' left out (T5b), and the elements
    // the list's searches met over the run (its work, T5c).
    const int size = decomp_->size();
    constexpr int kPer = 7;
    const double mine[kPer] = {static_cast<double>(dem_->particles().owned), local,
                               static_cast<double>(dem_->halo_bytes_sent()), static_cast<double>(dem_->list_relists()),
                               static_cast<double>(dem_->listed_elements()),
                               static_cast<double>(dem_->ghost_elements_left_out()),
                               static_cast<double>(dem_->list_tests())};
    std::vector<double> all(kPer * static_cast<std::size_t>(size));
    MPI_Allgather(mine, kPer, MPI_DOUBLE, all.data(), kPer, MPI_DOUBLE, comm);
    nlohmann::json per_rank{{"bodies", nlohmann::json::array()}, {"work", nlohmann::json::array()},
                            {"halo_bytes_sent", nlohmann::json::array()},
                            {"neighbor_list_relists", nlohmann::json::array()},
                            {"listed_elements", nlohmann::json::array()},
                            {"ghost_elements_left_out", nlohmann::json::array()},
                            {"neighbor_list_tests", nlohmann::json::array()}};
    for (int r = 0; r < size; ++r) {
      per_rank["bodies"].push_back(static_cast<long>(all[kPer * r]));
      per_rank["work"].push_back(all[kPer * r + 1]);
      per_rank["halo_bytes_sent"].push_back(static_cast<long>(all[kPer * r + 2]));
      per_rank["neighbor_list_relists"].push_back(static_cast<long>(all[kPer * r + 3]));
      per_rank["listed_elements"].push_back(static_cast<long>(all[kPer * r + 4]));
      per_rank["ghost_elements_left_out"].push_back(static_cast<long>(all[kPer * r + 5]));
      per_rank["neighbor_list_tests"].push_back(static_cast<long>(all[kPer * r + 6]));
    }
    s["per_rank"] = per_rank;
    if (balance_.enabled) s["balance"] = balance_.summary();
  }
  s["quantities"] = q;
  // Mesh walls: the load the bodies put on each at the last step, and a pivot's angle and speed.
  dem_->sum_mesh_loads();
  if (!dem_->walls().meshes().empty()) {
    nlohmann::json meshes = nlohmann::json::array();
    for (const auto& m : dem_->walls().meshes()) {
      nlohmann::json e{{"key", m.key},
                       {"force", {m.force.x, m.force.y, m.force.z}},
                       {"moment_about_origin", {m.moment.x, m.moment.y, m.moment.z}}};
      if (m.motion == MeshWall::Motion::pivot) {
        e["angle"] = m.theta;
        e["angular_velocity"] = m.theta_dot;
      }
      meshes.push_back(e);
    }
    s["mesh_walls"] = meshes;
  }
  if (!dem_->free_spheres().empty()) {
    nlohmann::json spheres = nlohmann::json::array();
    for (const auto& b : dem_->free_spheres())
      spheres.push_back({{"key", b.key},
                         {"position", {b.x.x, b.x.y, b.x.z}},
                         {"velocity", {b.v.x, b.v.y, b.v.z}},
                         {"angular_velocity", {b.omega.x, b.omega.y, b.omega.z}},
                         {"contact_force", {b.force.x, b.force.y, b.force.z}},
                         {"mass", b.mass}});
    s["free_spheres"] = spheres;
  }
  s["body_steps_per_second_per_core"] = static_cast<double>(stats.bodies) * s["steps_this_run"].get<double>() /
                                        std::max(s["loop_seconds"].get<double>(), 1e-9) / decomp_->size();
  s["output"] = {{"checkpoint", "checkpoint.h5"}, {"snapshots", snapshots_->count() ? "snapshots/particles.xmf" : ""}};
}

SettleCriterion::SettleCriterion(const ConfigNode& section, bool required) {
  if (!required && !section.has("settled_kinetic_energy")) {
    if (section.has("min_time")) section.fail("min_time", "set only with settled_kinetic_energy");
    return;
  }
  energy_ = section.real("settled_kinetic_energy", Dim::energy, Range::positive());
  min_time_ = section.real("min_time", Dim::time, Range::non_negative(), 0.0);
}

bool SettleCriterion::check(const DemStats& s, double time) {
  if (!settled_ && enabled() && time >= min_time_ && s.kinetic_translational + s.kinetic_rotational < energy_) {
    settled_ = true;
    settle_time_ = time;
  }
  return settled_;
}

void SettleCriterion::save(CheckpointExtras& e) const {
  e["settled"] = settled_ ? 1.0 : 0.0;
  e["settle_time"] = settle_time_;
}

void SettleCriterion::restore(const CheckpointExtras& e) {
  if (e.count("settled")) settled_ = e.at("settled") != 0;
  if (e.count("settle_time")) settle_time_ = e.at("settle_time");
}

void SettleCriterion::report(nlohmann::json& q, double time) const {
  q["settled"] = settled_;
  q["settle_time"] = settled_ ? settle_time_ : time;
}

}  // namespace tessera
