// SPDX-License-Identifier: MIT
// A scene: what `tessera run` runs. Each builds its solvers from the case in its constructor (every
// key read there, so bad input stops the run before anything is written), runs to the end, writes
// DIR/summary.json and returns it. Every scene runs in the shared loop of app/run_loop.hpp
// (SteppedScene): dry scenes derive from DemScene, the flow scene is FlowScene.
#pragma once
#include <mpi.h>

#include <array>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "app/signals.hpp"
#include "core/config.hpp"
#include "core/decomposition.hpp"
#include "core/vec3.hpp"

namespace tessera {

struct RunOptions {
  std::string output_dir;          // created once set-up has succeeded
  std::string resolved_case_yaml;  // written there as case.resolved.yaml
  std::optional<std::string> restart;
  bool quiet = false;
};

class Scene {
 public:
  virtual ~Scene() = default;
  virtual const char* name() const = 0;
  // Runs to the end; returns the summary (also written to DIR/summary.json).
  virtual nlohmann::json run(const RunOptions& options, const nlohmann::json& resolved_case) = 0;
};

// The case's `domain` section: box_min, box_max (checked), process_grid (0 = the grid chooses),
// cuts (optional: {x: [...], y: [...], z: [...]}, the interior cut planes along each direction,
// which fix the grid there; docs/design.md).
struct DomainSpec {
  Vec3 lo, hi;
  std::array<int, 3> grid{0, 0, 0};
  Decomposition::Cuts cuts;
};
inline DomainSpec read_domain(const ConfigNode& root) {
  const ConfigNode domain = root.section("domain");
  DomainSpec s;
  s.lo = domain.vec3("box_min", Dim::length);
  s.hi = domain.vec3("box_max", Dim::length);
  for (int d = 0; d < 3; ++d)
    if (!(s.hi[d] > s.lo[d])) domain.fail("box_max", "larger than box_min in every direction");
  if (domain.has("process_grid")) {
    const auto g = domain.integers("process_grid", 3, 0, 1 << 20);
    s.grid = {int(g[0]), int(g[1]), int(g[2])};
  }
  if (const auto cuts = domain.optional_section("cuts"))
    for (int d = 0; d < 3; ++d)
      if (cuts->has(std::string(1, "xyz"[d]))) s.cuts[d] = cuts->reals(std::string(1, "xyz"[d]), Dim::length);
  return s;
}

// Collective poll of a run loop, every few steps: has a stop signal (SIGTERM, SIGUSR1) reached any
// rank, and is a progress line due by rank 0's clock? Every rank gets the same answer.
struct RunPoll {
  bool stop = false, progress = false;
};
inline RunPoll poll_run(MPI_Comm comm, bool root, double wall_seconds, double last_progress, double interval) {
  int flags[2] = {stop_requested() ? 1 : 0, (root && wall_seconds - last_progress >= interval) ? 1 : 0};
  MPI_Allreduce(MPI_IN_PLACE, flags, 2, MPI_INT, MPI_MAX, comm);
  return {flags[0] != 0, flags[1] != 0};
}

// Builds the scene the case names (key `scene`).
std::unique_ptr<Scene> make_scene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir);

}  // namespace tessera
