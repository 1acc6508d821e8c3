// SPDX-License-Identifier: MIT
// A scene: what `tessera run` runs. Each builds its solvers from the case in its constructor (every
// key read there, so bad input stops the run before anything is written), runs to the end, writes
// DIR/summary.json and returns it. Dry scenes derive from DemScene; the flow scene is FlowScene.
#pragma once
#include <mpi.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/config.hpp"

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

// Builds the scene the case names (key `scene`).
std::unique_ptr<Scene> make_scene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir);

}  // namespace tessera
