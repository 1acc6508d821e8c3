// SPDX-License-Identifier: MIT
// The bodies of `scene: coupled` (issue 15, src/coupling): what the flow scene (scene_flow.cpp) adds
// when the case has bodies. Sections solid (as a dry scene's), bodies (file: a Tessera checkpoint,
// e.g. a settled bed; or list: bodies one by one), coupling (CouplingSettings) and, for the
// drop-impact scene (app/drop_impact.hpp), drop and crater.
//
// It owns the DEM and the coupled solver, and answers the flow scene's run-loop hooks for its part:
//   start          the bodies from the file, the list or a restart; the drop placed over the bed
//   begin          the coupled state (C4, C7), its outputs (DIR/snapshots, crater.csv) and checks
//   step           one CoupledSolver::step, with this run's statistics
//   check          every run.check_interval: finite, in the box, overlaps bounded; at rest?
//   snapshot       the bodies at a field snapshot, DIR/scene.xmf (fields and bodies in one series)
//   checkpoint     DIR/checkpoint_bodies.h5 beside the flow's DIR/checkpoint.h5
//   summarise      bodies, solid phase, fluid loads, pore liquid and coupling into summary.json
#pragma once
#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "app/dem_scene.hpp"
#include "app/drop_impact.hpp"
#include "app/run_loop.hpp"
#include "core/config.hpp"
#include "coupling/coupled_step.hpp"
#include "fluid/fluid_io.hpp"
#include "solid/dem_io.hpp"

namespace tessera {

class SceneBodies {
 public:
  // Reads sections solid, bodies, coupling, drop, crater and run's body checks.
  SceneBodies(const ConfigNode& root, const std::string& case_dir, const Decomposition& decomp, FlowSolver& flow);

  // The bodies (from `restart`, the bodies' file or the list) and the coupled solver; the drop's
  // liquid, when the case has one and this is not a restart (it is then in the flow's state).
  std::optional<DropShape> start(const std::optional<std::string>& restart);
  // After the flow's initial state: the coupled state and the outputs in `dir`.
  void begin(const std::optional<std::string>& restart, const std::string& dir);
  // The solid fraction (and with C7 the liquid content) with the flow's fields.
  void add_fields(FieldSeries& fields) const;
  void sample_crater();  // the crater's row now (the bed before the drop), if the case measures one
  // The lines the run prints at its start (rank 0); `drop_centre`: the drop's place, if placed.
  void print_start(const std::optional<Vec3>& drop_centre) const;
  CoupledStepStats step(double dt);
  // Every run.check_interval (collective): true once the bodies are at rest; `fail` on a body out of
  // the box, a non-finite state or an overlap over the bound.
  bool check(const std::function<void(const std::string&)>& fail);
  void snapshot(const FieldSeries& fields, bool resuming);
  void write_checkpoint(const std::string& flow_checkpoint) const;
  // Collective, after the cut planes moved and the flow was repartitioned and its state read back
  // from `flow_state` (a flow checkpoint with checkpoint_fields()): the bodies move to their new
  // ranks (DemSolver::rebalance), the coupled solver is made again on the new grid as at a restart
  // (the liquid content from `flow_state`), taking over this run's record. Then add_fields again.
  void repartition(const std::string& flow_state);
  // The bodies' part of a rank's work for balancing (issue 19): DemSolver::work scaled by the last
  // flow step's sub-steps (the DEM's work per flow step).
  std::vector<WorkSample> work() const;
  std::size_t halo_bytes_sent() const { return dem_->halo_bytes_sent(); }  // the DEM's ghosts and migrations
  std::size_t listed_elements() const { return dem_->listed_elements(); }  // the DEM list's last binning (T5b)
  std::size_t ghost_elements_left_out() const { return dem_->ghost_elements_left_out(); }
  std::size_t list_tests() const { return dem_->list_tests(); }  // the DEM list's work over the run (T5c)
  // The busy seconds of the bodies' stages so far (DEM sub-steps, solid fraction, fluid force, pore
  // liquid, correction), this rank.
  double busy_seconds();
  double contact_reach() const { return dem_->contact_reach(); }
  bool bodies_fixed() const { return coupling_.fixed_bodies; }
  // The flow checkpoint's extra cell fields (the liquid in the cells' fluid part, C7).
  std::vector<NamedCellField> checkpoint_fields() const;
  std::string series_header() const;
  std::string series_row();  // collective
  std::string progress();    // collective
  void summarise(nlohmann::json& s, long steps_run, double liquid_volume, const FieldSeries& fields);

  // The liquid volume of the coupled scene (the liquid content's sum with C7, else the flow's).
  double liquid_volume() const;
  PhaseTimers& timers() { return coupled_->timers(); }

 private:
  void create_bodies();
  // Collective: the lowest id of a body whose centre lies outside the box (or none), with its centre.
  std::optional<std::pair<std::int64_t, Vec3>> body_outside() const;
  CheckpointExtras extras() const;
  void restore_extras(const CheckpointExtras& e);
  double free_liquid_volume() const;
  void write_scene_index(const FieldSeries& fields) const;

  // A body of `bodies.list`.
  struct BodySpec {
    int shape = 1, material = 0;
    Vec3 x, v, omega;
    Quaternion q;
    double density = 0;
  };

  const Decomposition& decomp_;
  FlowSolver& flow_;
  std::unique_ptr<DemSolver> dem_;
  std::unique_ptr<CoupledSolver> coupled_;
  CouplingSettings coupling_;
  std::string bodies_file_;
  std::vector<BodySpec> body_list_;
  double check_interval_ = 0, max_overlap_ratio_ = 0.5;
  Schedule checks_;
  std::unique_ptr<SnapshotSeries> bodies_out_;
  std::string output_dir_;
  // This run's statistics.
  int last_substeps_ = 0;
  long substeps_total_ = 0;
  double free_liquid0_ = 0;  // liquid outside the bodies at the start of this run
  int pore_passes_max_ = 0;  // the liquid stage's largest number of passes and residual (C7)
  double pore_residual_max_ = 0;
  std::array<double, 2> step_range_{std::numeric_limits<double>::infinity(), 0.0};
  SettleCriterion rest_;  // bodies.settled_kinetic_energy: the run ends when the bodies are at rest
  // The drop-impact scene (sections drop and crater).
  std::optional<DropOnBed> drop_;
  std::optional<CraterMonitor> crater_;
};

}  // namespace tessera
