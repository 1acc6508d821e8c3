// SPDX-License-Identifier: MIT
// Running a scene in-process on a sub-communicator and gathering its final body states, for
// parallel-equivalence and restart tests.
#pragma once
#include <mpi.h>

#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "app/scene.hpp"

namespace tessera::test {

int world_rank();
int world_size();

// Full packed state (ParticleStore::pack) of every body, by id; filled on world rank 0 only.
using BodyStates = std::map<long, std::vector<double>>;

// Runs any scene from case text with overrides on the first `ranks` ranks of MPI_COMM_WORLD
// (quiet, into output_dir); `after` sees the finished scene on those ranks. Returns the summary
// there (empty elsewhere); every world rank must call it.
nlohmann::json run_case_on(int ranks, const std::string& yaml, const std::vector<std::string>& sets,
                           const std::string& output_dir, std::optional<std::string> restart = std::nullopt,
                           const std::function<void(Scene&, MPI_Comm)>& after = {});

// Runs a dry scene the same way and gathers its final body states.
BodyStates run_scene_on(int ranks, const std::string& yaml, const std::vector<std::string>& sets,
                        const std::string& output_dir, std::optional<std::string> restart = std::nullopt);

// The text of a file (a shipped case read by a test).
std::string file_text(const std::string& path);

// The last file of DIR with extension `ext` (".h5") in name order: a run's last snapshot.
std::string last_file(const std::string& dir, const std::string& ext);

// Number of bodies whose states differ bitwise (missing bodies count too); prints the first few.
long count_differences(const BodyStates& a, const BodyStates& b, const char* what);

}  // namespace tessera::test
