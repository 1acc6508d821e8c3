// SPDX-License-Identifier: MIT
// A dry scene: a DEM in a box, run by the shared run loop (app/run_loop.hpp: snapshots,
// checkpoints, signals, progress, summary.json); every run.check_interval it checks the state's
// health and asks the scene whether it is done. Concrete scenes create their bodies, say when they
// are done and report their quantities.
//
// Case sections read here: domain, solid, run, output. All keys are read in the constructor, so
// that bad input stops the run before any output is written.
#pragma once
#include <mpi.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "app/balance_record.hpp"
#include "app/run_loop.hpp"
#include "app/scene.hpp"
#include "core/config.hpp"
#include "core/decomposition.hpp"
#include "solid/dem_io.hpp"
#include "solid/dem_solver.hpp"

namespace tessera {

class DemScene : public SteppedScene {
 public:
  DemScene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir);

  DemSolver& dem() { return *dem_; }
  int rank() const { return decomp_->rank(); }

 protected:
  virtual void create_bodies() = 0;
  // True when create_bodies loaded a saved state (forces, histories, order keys): set-up keeps it.
  virtual bool continues_state() const { return false; }
  // Called every run.check_interval of simulated time (collective): true ends the run.
  virtual bool finished(const DemStats& stats) {
    (void)stats;
    return false;
  }
  virtual void finish(const RunOptions& options) { (void)options; }
  // After every step (all ranks): per-step quantities (the bunker shot's impulse and release).
  virtual void on_step(const RunOptions& options) { (void)options; }
  virtual void quantities(nlohmann::json& q) { (void)q; }
  virtual CheckpointExtras extras() const { return {}; }
  virtual void restore(const CheckpointExtras& e) { (void)e; }

  std::string resolve_path(const std::string& p) const;
  // Collective: stops the run with a message and a dump of the failing state when the state is not
  // finite or an overlap exceeds the bound (the last periodic checkpoint is the last good state).
  void check_health(const DemStats& s, const RunOptions& opt);
  // Every pair among these body materials, and with every wall, must have contact parameters:
  // checked at set-up, before any output.
  void require_pairs(const std::vector<int>& body_materials) const;

  std::unique_ptr<Decomposition> decomp_;
  std::unique_ptr<DemSolver> dem_;
  double check_interval_ = 0;
  double max_overlap_ratio_ = 0.5;  // blow-up bound, checked every check_interval
  std::string case_dir_;

 private:
  // The run loop's hooks (app/run_loop.hpp).
  const Decomposition& decomposition() const override { return *decomp_; }
  void start(const RunOptions& opt) override;
  void begin_output(const RunOptions& opt) override;
  double time() const override { return dem_->time(); }
  long steps() const override { return dem_->steps(); }
  double last_dt() const override { return dem_->dt(); }
  void step(const RunOptions& opt) override;
  bool after_step(const RunOptions& opt) override;
  void write_snapshot() override;
  void write_checkpoint(const std::string& path) override;
  std::string progress() override;
  void end_output(const RunOptions& opt) override;
  void summarise(nlohmann::json& s) override;
  PhaseTimers& phase_timers() override { return dem_->timers(); }

  // Load balance (issue 19, case section `balance`, app/balance_record.hpp): every `interval` steps
  // the ranks' work (DemSolver::work, or measured time) is compared; above `threshold` the cut planes
  // move to balance it (core/balance.hpp) and the bodies follow (DemSolver::rebalance). The time
  // measure shares a rank's busy seconds over its bodies by their counts (what the counts miss: the
  // club's mesh contacts, struck grains' rebuilds; the cuts vary from run to run, the results do not).
  BalanceRecord balance_;
  void balance_if_due();

  std::unique_ptr<SnapshotSeries> snapshots_;
  Schedule checks_;
  long cross_rank_contacts_ = 0;  // summed over the checks: evidence that the ranks shared contacts
};

// When a scene's bodies are at rest: the total kinetic energy below `settled_kinetic_energy` once
// `min_time` has passed (keys of the scene's section; checked every run.check_interval). The
// deposition requires it; a bed may set it to end a settling run (the bunker ball's drop) early.
class SettleCriterion {
 public:
  SettleCriterion() = default;
  SettleCriterion(const ConfigNode& section, bool required);
  bool enabled() const { return energy_ > 0; }
  // True once the bodies have settled (and from then on).
  bool check(const DemStats& s, double time);
  void save(CheckpointExtras& e) const;
  void restore(const CheckpointExtras& e);
  // quantities: settled, settle_time (the time now when not settled).
  void report(nlohmann::json& q, double time) const;

 private:
  double energy_ = 0, min_time_ = 0, settle_time_ = 0;
  bool settled_ = false;
};

// Builds a dry scene (deposition, bed): for callers that need its DEM (tests, tools).
std::unique_ptr<DemScene> make_dem_scene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir);

}  // namespace tessera
