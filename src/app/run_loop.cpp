// SPDX-License-Identifier: MIT
#include "app/run_loop.hpp"

#include <cstdio>
#include <filesystem>

#include "core/text_file.hpp"
#include "tessera_version.hpp"

namespace tessera {

void SteppedScene::read_loop_keys(const ConfigNode& root, bool end_time_required) {
  const ConfigNode run = root.section("run");
  if (end_time_required || run.has("end_time")) end_time_ = run.real("end_time", Dim::time, Range::positive());
  if (run.has("max_steps")) max_steps_ = run.integer("max_steps", 1, 1L << 50);
  if (const auto out = root.optional_section("output")) {
    snapshot_interval_ = out->real("snapshot_interval", Dim::time, Range::non_negative(), 0.0);
    checkpoint_interval_ = out->real("checkpoint_interval", Dim::time, Range::non_negative(), 0.0);
    progress_interval_ = out->real("progress_interval", Dim::time, Range::positive(), 10.0);
    land_on_times_ = out->flag("land_on_times", true);
  }
}

std::vector<double> SteppedScene::landing_targets() const {
  if (!land_on_times_) return {end_time_.value_or(1e300)};
  return {end_time_.value_or(1e300), snapshots_.next(), checkpoints_.next()};
}

void SteppedScene::end_output(const RunOptions& opt) { write_checkpoint(opt.output_dir + "/checkpoint.h5"); }

nlohmann::json SteppedScene::run(const RunOptions& opt, const nlohmann::json& resolved_case) {
  const Decomposition& decomp = decomposition();
  MPI_Comm comm = decomp.comm();
  const bool root = decomp.rank() == 0;
  const auto wall_start = std::chrono::steady_clock::now();
  auto wall = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count(); };

  start(opt);
  // Set-up succeeded: only now does the run leave anything on disk.
  if (root) {
    std::filesystem::create_directories(opt.output_dir);
    if (!opt.resolved_case_yaml.empty())
      write_file_atomically(opt.output_dir + "/case.resolved.yaml", opt.resolved_case_yaml);
  }
  MPI_Barrier(comm);
  begin_output(opt);
  start_steps_ = steps();
  snapshots_ = Schedule(snapshot_interval_, time(), last_dt());
  checkpoints_ = Schedule(checkpoint_interval_, time(), last_dt());
  double last_progress = 0;
  MPI_Barrier(comm);
  const double loop_start = wall();

  while (true) {
    // A fixed step ends within half a step of end_time; an adaptive one lands on it.
    if (end_time_ && time() >= *end_time_ - 0.5 * last_dt()) break;
    if (max_steps_ && steps() >= *max_steps_) break;
    step(opt);
    if (after_step(opt)) break;
    if (snapshots_.due(time(), last_dt())) {
      auto t = phase_timers().scope("output");
      write_snapshot();
    }
    if (checkpoints_.due(time(), last_dt())) {
      auto t = phase_timers().scope("output");
      write_checkpoint(opt.output_dir + "/checkpoint.h5");
    }
    if (steps() % poll_every_ == 0) {
      const RunPoll poll = poll_run(comm, root, wall(), last_progress, progress_interval_);
      if (poll.stop) {
        status_ = "interrupted";
        break;
      }
      if (poll.progress) {
        last_progress = wall();
        const std::string line = progress();
        if (root && !opt.quiet) {
          const double rate = static_cast<double>(steps() - start_steps_) / std::max(1e-9, wall() - loop_start);
          std::printf("step %ld  t %.5g s  %s  %.3g steps/s  wall %.1f s", steps(), time(), line.c_str(), rate, wall());
          if (end_time_) std::printf("  ETA %.0f s", (*end_time_ - time()) / last_dt() / std::max(rate, 1e-9));
          std::printf("\n");
          std::fflush(stdout);
        }
      }
    }
  }
  MPI_Barrier(comm);
  double loop_seconds = wall() - loop_start;
  {
    auto t = phase_timers().scope("output");
    end_output(opt);
  }

  nlohmann::json s;
  s["code_version"] = kTesseraVersion;
  s["scene"] = name();
  s["status"] = status_;
  s["ranks"] = decomp.size();
  s["process_grid"] = decomp.dims();
  s["cuts"] = {decomp.cuts(0), decomp.cuts(1), decomp.cuts(2)};  // every sub-domain face, per direction
  s["steps"] = steps();
  s["steps_this_run"] = steps() - start_steps_;
  s["time"] = time();
  MPI_Bcast(&loop_seconds, 1, MPI_DOUBLE, 0, comm);
  s["loop_seconds"] = loop_seconds;  // the time-step loop only, as LAMMPS' "Loop time"
  summarise(s);
  double wall_seconds = wall();
  MPI_Bcast(&wall_seconds, 1, MPI_DOUBLE, 0, comm);
  s["wall_seconds"] = wall_seconds;
  nlohmann::json timers;
  for (const auto& [phase, t] : phase_timers().reduce(comm))
    timers[phase] = {{"min", t.min}, {"avg", t.avg}, {"max", t.max}, {"per_rank", t.per_rank}};
  s["timers"] = timers;
  s["case"] = resolved_case;
  if (root) write_file_atomically(opt.output_dir + "/summary.json", s.dump(2) + "\n");
  return s;
}

}  // namespace tessera
