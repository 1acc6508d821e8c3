// SPDX-License-Identifier: MIT
// The run loop every scene uses (dry, flow, and the coupled one to come): set-up before any output,
// the clock, the output schedule (snapshots and checkpoints at fixed intervals of simulated time),
// stop signals (SIGTERM, SIGUSR1: a batch queue's warning) and progress lines polled collectively,
// the final checkpoint, and summary.json's common part. A scene supplies its step and its outputs
// through the hooks below, in the order the loop calls them:
//
//   start              restart or initial state (collective; bad input throws before any output)
//   (the output directory and case.resolved.yaml are written)
//   begin_output       banner, series headers, the first snapshot
//   loop until end_time (time >= end - dt/2) or max_steps:
//     step             one step; a scene with an adaptive dt lands on landing_targets()
//     after_step       per-step checks and series; true ends the run (settled, released)
//     snapshot, checkpoint when due
//     every poll_every steps: stop signal -> status "interrupted"; progress line when due
//   end_output         final checkpoint and snapshot
//   summarise          the scene's keys (quantities, counters); the loop adds the common ones
//
// Case keys read here (section run: end_time, max_steps; section output: snapshot_interval,
// checkpoint_interval, progress_interval, land_on_times) are the same for every scene.
//
// output.land_on_times (default true): an adaptive step is shortened to end on each snapshot and
// checkpoint time, so fields are written at exactly those times. The output schedule then changes
// the step sequence; a chaotic run (grains) answers that with a different result (the drop on sand:
// 27 % in the crater volume, docs/validation.md). false lands on the end time only: snapshots are
// written at the first step within half a step of their time (the file holds the actual time), and
// the answer does not depend on the output schedule nor on where a run was stopped and restarted.
#pragma once
#include <mpi.h>

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "app/scene.hpp"
#include "core/config.hpp"
#include "core/decomposition.hpp"
#include "core/timers.hpp"

namespace tessera {

// Event times at a fixed interval of simulated time: k * interval for k = 1, 2, ... (computed by
// multiplication, not by accumulation); an interval of 0 never fires. A step fires the event when
// it ends within half a step of the event time.
class Schedule {
 public:
  Schedule() = default;
  // The first event not yet fired at time_now, the step just taken being last_dt: an event within
  // half that step after time_now fired with it (due()), so a restart does not fire it again.
  Schedule(double interval, double time_now, double last_dt = 0) : interval_(interval) {
    if (interval_ > 0) k_ = static_cast<long>(std::floor((time_now + 0.5 * last_dt) / interval_ + 1e-9)) + 1;
  }
  double next() const { return interval_ > 0 ? static_cast<double>(k_) * interval_ : 1e300; }
  // True (and moves on to the next event time) when `time` is within dt/2 of the event time or past it.
  bool due(double time, double dt) {
    if (interval_ <= 0 || time < next() - 0.5 * dt) return false;
    ++k_;
    return true;
  }

 private:
  double interval_ = 0;
  long k_ = 0;
};

class SteppedScene : public Scene {
 public:
  nlohmann::json run(const RunOptions& options, const nlohmann::json& resolved_case) final;

 protected:
  // Reads run.end_time (required when `end_time_required`), run.max_steps and the output section.
  void read_loop_keys(const ConfigNode& root, bool end_time_required);

  virtual const Decomposition& decomposition() const = 0;
  virtual void start(const RunOptions& opt) = 0;
  virtual void begin_output(const RunOptions& opt) { (void)opt; }
  virtual double time() const = 0;
  virtual long steps() const = 0;
  virtual double last_dt() const = 0;  // the step just taken (a fixed step: the step; none yet: 0)
  virtual void step(const RunOptions& opt) = 0;
  virtual bool after_step(const RunOptions& opt) {
    (void)opt;
    return false;
  }
  virtual void write_snapshot() {}
  virtual void write_checkpoint(const std::string& path) = 0;
  // A progress line's body (rank 0 prints it, with the rate and wall time); collective.
  virtual std::string progress() = 0;
  virtual void end_output(const RunOptions& opt);
  // The scene's own summary keys (collective): `quantities` and any counters.
  virtual void summarise(nlohmann::json& summary) = 0;
  virtual PhaseTimers& phase_timers() = 0;
  // Output times an adaptive step should land on: the end time, then (output.land_on_times) the next
  // snapshot and the next checkpoint.
  std::vector<double> landing_targets() const;

  std::optional<double> end_time_;
  std::optional<long> max_steps_;
  double snapshot_interval_ = 0, checkpoint_interval_ = 0, progress_interval_ = 10;
  bool land_on_times_ = true;
  long poll_every_ = 100;  // steps between collective polls
  long start_steps_ = 0;
  std::string status_ = "completed";

 private:
  Schedule snapshots_, checkpoints_;
};

}  // namespace tessera
