// SPDX-License-Identifier: MIT
// The case section `balance` (issue 19) and the record of what it did, for every scene that moves
// its cut planes: the dry scenes (dem_scene.cpp: bodies follow by DemSolver::rebalance) and the flow
// and coupled scenes (scene_flow.cpp: the grid, its fields and the bodies follow). Keys: `enabled`
// (false), `interval` (steps between checks), `threshold` (largest rank's work over the mean above
// which the cuts move), `measure` (`counts`: work counted, the same cuts on every run; `time`: the
// ranks' busy seconds since the last check, shared over their work in proportion to the counts).
// What the work is and how the state follows is the scene's; the schedule, the threshold and the
// summary are here.
#pragma once
#include <array>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/config.hpp"

namespace tessera {

struct BalanceRecord {
  bool enabled = false;
  long interval = 1000;
  double threshold = 1.1;
  bool measure_time = false;
  std::array<double, 2> busy_at_check{};  // time: the rank's busy seconds at the last check, per part
  long checks = 0, rebalances = 0;
  double first_imbalance = 0, last_before = 0, last_after = 0;
  nlohmann::json events = nlohmann::json::array();  // the first 100 rebalances: step, before, after

  // Reads the section if the case has one (every key checked).
  void read(const ConfigNode& root);
  // A check is due after `steps` steps (and there is more than one rank).
  bool due(long steps, int ranks) const { return enabled && ranks > 1 && steps % interval == 0; }
  // The time measure: the busy seconds since the last check, given the rank's total so far (`part`:
  // a scene with two kinds of work, the flow's cells and the bodies, keeps one clock for each).
  double busy_since(double busy_total, int part = 0) {
    const double since = busy_total - busy_at_check[part];
    busy_at_check[part] = busy_total;
    return since;
  }
  // A check's imbalance; true when it is over the threshold (the cuts should move).
  bool over_threshold(double before);
  // The cuts moved at `step`; `after`: the new cuts' imbalance, when known now (counts).
  void rebalanced(long step, double before, std::optional<double> after);
  // summary.json's `balance`.
  nlohmann::json summary() const;
};

}  // namespace tessera
