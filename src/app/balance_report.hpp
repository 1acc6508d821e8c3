// SPDX-License-Identifier: MIT
// `tessera balance CASE.yaml --bodies CHECKPOINT.h5 --ranks 4,16,64` (issue 19): how evenly the
// bodies of a checkpoint would spread over P ranks of the case's box, with equal slabs and with
// balanced cut planes (core/balance.hpp), computed on one process without running P. The process
// grid is the one a run on P ranks would choose (Decomposition::choose_dims, with the case's
// domain.process_grid and plane mode); slabs are kept at least the contact reach wide (2 r_max plus
// the skin) and, in flow scenes, on the fluid's cell faces. The work is what a run's balance counts:
// 1 plus the listed pairs of each body (DemSolver::work). A coupled case (`scene: coupled`) adds its
// flow cells, balance.cell_weight each, and weighs the bodies by coupling.substeps (required: the
// DEM sub-steps of a flow step), and searches the cuts as its run does (FlowScene::balance_if_due).
// A blast case (`scene: blast`, no --bodies) reports its elements instead: the work of a macro step
// per rank at the initial time-step levels with equal slabs, balanced cuts and a METIS partition of
// the element graph, and the bonds each cuts (src/fracture/element_partition.hpp).
#pragma once
#include <string>
#include <vector>

namespace tessera {

struct BalanceRequest {
  std::string case_file, bodies_file;
  std::vector<std::string> sets;
  std::vector<int> ranks;
  std::string json_out;  // optional: the table as JSON
};

// Prints the table; returns 0.
int balance_report(const BalanceRequest& request);

}  // namespace tessera
