// SPDX-License-Identifier: MIT
// tessera: impacts on granular beds.
//
//   tessera run CASE.yaml [--set section.key=value ...] [--output DIR] [--restart CHECKPOINT] [--quiet]
//               [--petsc "-poisson_pc_type gamg ..."]
//   tessera balance CASE.yaml [--bodies CHECKPOINT.h5] --ranks 4,16,64 [--set ...] [--json FILE]
//   tessera info
// Exit codes: 0 done, 2 bad input (nothing written), 3 interrupted by a signal (checkpoint written),
// 4 blow-up (failure.h5 written), 1 other failure (MPI_Abort).
//
// Sample run: mpirun -n 2 build/bin/tessera run cases/deposition/small.yaml --output runs/dep
// Afterwards: DIR/summary.json (quantities, timers, resolved case), DIR/snapshots/particles.xmf
// (ParaView), DIR/checkpoint.h5 (restart with --restart), DIR/bed.data (LAMMPS data file).
#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "app/balance_report.hpp"
#include "app/dem_scene.hpp"
#if defined(TESSERA_HAVE_PETSC)
#include <petscsys.h>
#endif
#include "app/signals.hpp"
#include "app/yaml_json.hpp"
#include "core/config.hpp"
#include "core/errors.hpp"
#include "solid/dem_io.hpp"
#include "tessera_version.hpp"

namespace fs = std::filesystem;
using namespace tessera;

namespace {

const char* kUsage =
    "usage: tessera run CASE.yaml [--set section.key=value ...] [--output DIR] [--restart CHECKPOINT] [--quiet]\n"
    "                   [--petsc \"PETSc options\"]   (flow scenes: e.g. -poisson_ksp_monitor -poisson_pc_type gamg)\n"
    "       tessera balance CASE.yaml [--bodies CHECKPOINT.h5] --ranks 4,16,64 [--set ...] [--json FILE]\n"
    "                   (imbalance of the checkpoint's bodies on P ranks: equal slabs and balanced cuts;\n"
    "                    a blast case: its elements' work with slabs, balanced cuts and METIS)\n"
    "       tessera info\n";

struct Args {
  std::string command, case_file, output, petsc_options, bodies, json;
  std::vector<int> ranks;
  std::vector<std::string> sets;
  std::optional<std::string> restart;
  bool quiet = false;
};

Args parse_args(int argc, char** argv) {
  Args a;
  if (argc < 2) throw InputError("(command line)", "", std::string("a command\n") + kUsage);
  a.command = argv[1];
  for (int i = 2; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&](const char* flag) {
      if (i + 1 >= argc) throw InputError(flag, "", "needs a value");
      return std::string(argv[++i]);
    };
    if (s == "--set")
      a.sets.push_back(value("--set"));
    else if (s.rfind("--set=", 0) == 0)
      a.sets.push_back(s.substr(6));
    else if (s == "--output")
      a.output = value("--output");
    else if (s == "--restart")
      a.restart = value("--restart");
    else if (s == "--petsc")
      a.petsc_options += " " + value("--petsc");
    else if (s == "--bodies")
      a.bodies = value("--bodies");
    else if (s == "--json")
      a.json = value("--json");
    else if (s == "--ranks") {
      const std::string list = value("--ranks");
      std::size_t at = 0;
      while (at < list.size()) {
        const std::size_t comma = std::min(list.find(',', at), list.size());
        try {
          a.ranks.push_back(std::stoi(list.substr(at, comma - at)));
        } catch (const std::exception&) {
          throw InputError("--ranks", list, "rank counts separated by commas, e.g. 4,16,64");
        }
        if (a.ranks.back() < 1) throw InputError("--ranks", list, "positive rank counts");
        at = comma + 1;
      }
    } else if (s == "--quiet")
      a.quiet = true;
    else if (!s.empty() && s[0] != '-' && a.case_file.empty())
      a.case_file = s;
    else
      throw InputError("(command line)", s, std::string("a known option\n") + kUsage);
  }
  return a;
}

int run(const Args& args, int rank) {
  if (args.case_file.empty()) throw InputError("(command line)", "", std::string("a case file\n") + kUsage);
  Config config = Config::load(args.case_file, args.sets);
#if defined(TESSERA_HAVE_PETSC)
  // Command-line PETSc options go in after the case's (fluid.poisson.petsc_options), so they win.
  if (!args.petsc_options.empty() && PetscOptionsInsertString(nullptr, args.petsc_options.c_str()))
    throw InputError("--petsc", args.petsc_options, "PETSc options, e.g. \"-poisson_pc_type gamg\"");
#endif
  // Relative file paths (a bed, bodies, meshes) resolve against the case's directory. The resolved
  // case records it (case.resolved.yaml lives in the output directory), so that it runs again.
  const fs::path file_dir = fs::path(args.case_file).parent_path();
  const std::string case_dir = config.root().text(
      "case_directory", fs::absolute(file_dir.empty() ? fs::path(".") : file_dir).lexically_normal().string());
  auto scene = make_scene(config.root(), MPI_COMM_WORLD, case_dir);
  config.check_unused();  // every key was read: anything left is unknown

  RunOptions opt;
  opt.output_dir = args.output.empty() ? "runs/" + fs::path(args.case_file).stem().string() : args.output;
  opt.restart = args.restart;
  opt.quiet = args.quiet || std::getenv("CI") != nullptr;
  if (opt.restart && !fs::is_regular_file(*opt.restart))
    throw InputError("--restart", *opt.restart, "an existing checkpoint file");
  YAML::Emitter e;
  e << config.resolved();
  opt.resolved_case_yaml = std::string(e.c_str()) + "\n";
  install_stop_signal_handlers();
  const auto summary = scene->run(opt, yaml_to_json(config.resolved()));
  if (rank == 0) {
    std::printf("%s: %s after %ld steps, t = %.6g s, %.1f s wall\n", summary["scene"].get<std::string>().c_str(),
                summary["status"].get<std::string>().c_str(), summary["steps"].get<long>(),
                summary["time"].get<double>(), summary["wall_seconds"].get<double>());
    for (const auto& [k, v] : summary["quantities"].items()) std::printf("  %s: %s\n", k.c_str(), v.dump().c_str());
    const std::string snapshots = summary["output"]["snapshots"].get<std::string>();
    std::printf("output: %s (summary.json, checkpoint.h5%s)\n", opt.output_dir.c_str(),
                snapshots.empty() ? "" : (", " + snapshots).c_str());
  }
  return summary["status"] == "completed" ? 0 : 3;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
#if defined(TESSERA_HAVE_PETSC)
  PetscInitializeNoArguments();  // reads PETSC_OPTIONS; MPI stays ours
#endif
  int rank = 0, code = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  try {
    const Args args = parse_args(argc, argv);
    if (args.command == "info") {
      if (rank == 0)
        std::printf("tessera %s\nmodules: solid (DEM) on; fluid %s\n", kTesseraVersion,
                    kFluidModule ? "on (PETSc)" : "off (built without PETSc)");
    } else if (args.command == "run") {
      code = run(args, rank);
    } else if (args.command == "balance") {
      if (rank == 0) code = balance_report({args.case_file, args.bodies, args.sets, args.ranks, args.json});
    } else if (args.command == "--version") {
      if (rank == 0) std::printf("tessera %s\n", kTesseraVersion);
    } else if (args.command == "--help" || args.command == "help") {
      if (rank == 0) std::printf("%s", kUsage);
    } else {
      throw InputError("(command line)", args.command, std::string("a command: run, balance or info\n") + kUsage);
    }
  } catch (const InputError& e) {
    // Input is read identically on every rank, so every rank throws: report once, exit cleanly.
    if (rank == 0) std::fprintf(stderr, "tessera: %s\n", e.what());
    code = 2;
  } catch (const CollectiveRunError& e) {
    // Every rank decided this together (global reductions): report once, exit cleanly.
    if (rank == 0) std::fprintf(stderr, "tessera: %s\n", e.what());
    code = 4;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tessera (rank %d): %s\n", rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
#if defined(TESSERA_HAVE_PETSC)
  PetscFinalize();
#endif
  MPI_Finalize();
  return code;
}
