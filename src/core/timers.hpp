// SPDX-License-Identifier: MIT
// Phase timers. Each phase of a step has a name (the same names the step's stage list and the log
// use); summary.json reports min/avg/max over ranks so that load imbalance is visible.
#pragma once
#include <mpi.h>

#include <chrono>
#include <map>
#include <string>
#include <vector>

namespace tessera {

class PhaseTimers {
 public:
  struct Stats {
    double min = 0, avg = 0, max = 0;
    std::vector<double> per_rank;  // every rank's seconds, in rank order
  };

  void add(const std::string& phase, double seconds);
  double total(const std::string& phase) const;
  // Adds every phase of `other` as prefix + its name (a solver's phases inside a scene's stage).
  void merge(const PhaseTimers& other, const std::string& prefix) {
    for (const auto& [phase, t] : other.seconds_) seconds_[prefix + phase] += t;
  }
  // Collective over comm: every rank must call with the same phases (missing ones count as 0).
  std::vector<std::pair<std::string, Stats>> reduce(MPI_Comm comm) const;

  class Scope {
   public:
    Scope(PhaseTimers& t, const char* phase) : timers_(t), phase_(phase), start_(std::chrono::steady_clock::now()) {}
    ~Scope() { timers_.add(phase_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count()); }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    PhaseTimers& timers_;
    const char* phase_;
    std::chrono::steady_clock::time_point start_;
  };
  Scope scope(const char* phase) { return Scope(*this, phase); }

 private:
  std::map<std::string, double> seconds_;
};

}  // namespace tessera
