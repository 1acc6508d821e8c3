// SPDX-License-Identifier: MIT
#include "app/balance_record.hpp"

namespace tessera {

void BalanceRecord::read(const ConfigNode& root) {
  const auto b = root.optional_section("balance");
  if (!b) return;
  enabled = b->flag("enabled", false);
  interval = b->integer("interval", 1, 1L << 40, interval);
  threshold = b->real("threshold", Dim::none, Range::closed(1.0, 1e9), threshold);
  measure_time = b->choice("measure", {"counts", "time"}, "counts") == "time";
}

bool BalanceRecord::over_threshold(double before) {
  if (checks++ == 0) first_imbalance = before;
  return before > threshold;
}

void BalanceRecord::rebalanced(long step, double before, std::optional<double> after) {
  ++rebalances;
  last_before = before;
  last_after = after.value_or(before);
  if (events.size() < 100) {
    nlohmann::json e{{"step", step}, {"before", before}};
    if (after) e["after"] = *after;
    events.push_back(e);
  }
}

nlohmann::json BalanceRecord::summary() const {
  nlohmann::json s{{"measure", measure_time ? "time" : "counts"},
                   {"interval", interval},
                   {"threshold", threshold},
                   {"checks", checks},
                   {"rebalances", rebalances},
                   {"first_imbalance", first_imbalance},
                   {"last_before", last_before},
                   {"events", events}};
  if (!measure_time) s["last_after"] = last_after;
  return s;
}

}  // namespace tessera
