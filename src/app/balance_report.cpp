// SPDX-License-Identifier: MIT
#include "app/balance_report.hpp"

#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "app/blast_case.hpp"
#include "coupling/layout_cost.hpp"
#include "core/balance.hpp"
#include "core/config.hpp"
#include "core/decomposition.hpp"
#include "core/errors.hpp"
#include "core/h5_file.hpp"
#include "fluid/flow_solver.hpp"
#include "fluid/multigrid_plan.hpp"
#include "solid/rank_load.hpp"
#include "solid/rigid_rotation.hpp"
#include "solid/shape.hpp"

namespace tessera {

namespace {

// The blast's elements (issue 19): each partition's work per rank at the start, from the levels a
// run would choose (element_partition.hpp), on one process; with a checkpoint (--bodies), also the
// work of its state (the levels a macro step would take there, the intact bonds, the listed contact
// pairs) on each partition of the start's work (a run that never rebalances) and on a partition of
// that work itself (a rebalanced run).
int blast_balance_report(const BalanceRequest& rq, const ConfigNode& root) {
  const BlastCase c = read_blast_case(root, std::filesystem::path(rq.case_file).parent_path().string());
  const Decomposition one(MPI_COMM_SELF, c.lo, c.hi, {1, 1, 1});
  FractureSolver solver(one, build_bonded_block(c.mesh, c.settings.density), c.settings, c.hole);
  const ElementWork start = solver.work();
  ElementWork now;
  if (!rq.bodies_file.empty()) {
    read_blast_checkpoint(rq.bodies_file, MPI_COMM_SELF, solver);
    solver.setup(false);
    solver.take_levels();
    const FractureSolver::BalanceCheck check = solver.balance_check();
    now = check.work;
    std::printf("checkpoint %s: t = %.4g s, step %ld, %zu listed contact pairs\n", rq.bodies_file.c_str(), solver.time(),
                solver.steps(), check.list.pairs.size());
  }
  const BondedBlock& block = solver.block();
  std::printf("%zu elements, %zu bonds; work per macro step at the initial levels: %.0f element updates, %.0f bond "
              "evaluations x %.1f\n",
              block.size(), block.bonds.size(), [&] { double w = 0; for (double x : start.element) w += x; return w; }(),
              [&] { double w = 0; for (double x : start.bond) w += x; return w / kBondCostPerUpdate; }(),
              kBondCostPerUpdate);
  // Per partition: the macro step's imbalance (sum), the sub-steps' (every sub-step ends in an
  // exchange that waits for the busiest rank: substep_imbalance, element_partition.hpp), bonds cut.
  std::printf("%6s %10s %24s %24s %24s\n", "ranks", "grid", "slabs", "balanced", "metis");
  std::printf("%6s %10s", "", "");
  for (int k = 0; k < 3; ++k) std::printf(" %7s %7s %8s", "sum", "substep", "cut");
  std::printf("\n");
  nlohmann::json table = nlohmann::json::array();
  for (const int p : rq.ranks) {
    const auto dims = Decomposition::choose_dims(p, c.hi - c.lo, c.grid);
    nlohmann::json row{{"ranks", p}, {"grid", dims}};
    std::printf("%6d %4dx%dx%-3d", p, dims[0], dims[1], dims[2]);
    for (const Partition how : {Partition::slabs, Partition::balanced, Partition::metis}) {
      const std::vector<int> part = partition_elements(block, start, how, c.lo, c.hi, dims);
      const std::vector<double> work = part_work(block, start, part, p);
      const auto level_work = part_level_work(block, start, part, p);
      const double substeps = substep_imbalance(level_work);
      const long cut = cut_bonds(block, part);
      const LevelHalo halo = part_level_halo(block, start, part, p);
      if (!now.element.empty()) {  // the checkpoint's work on the start's partition, and repartitioned
        const std::vector<int> again = partition_elements(block, now, how, c.lo, c.hi, dims);
        const auto kept = part_level_work(block, now, part, p), moved = part_level_work(block, now, again, p);
        row["checkpoint"][partition_name(how)] = {{"start_partition_substep_imbalance", substep_imbalance(kept)},
                                                  {"repartitioned_substep_imbalance", substep_imbalance(moved)},
                                                  {"repartitioned_cut_bonds", cut_bonds(block, again)},
                                                  {"start_partition_level_work", kept},
                                                  {"repartitioned_level_work", moved}};
      }
      std::printf(" %7.3f %7.3f %8ld", imbalance(work), substeps, cut);
      row[partition_name(how)] = {{"imbalance", imbalance(work)},
                                  {"substep_imbalance", substeps},
                                  {"substep_time", substep_time(level_work)},
                                  {"level_imbalance", level_imbalance(level_work)},
                                  {"level_work", level_work},
                                  {"cut_bonds", cut},
                                  {"level_halo_sent", halo.sent},
                                  {"halo_neighbours", halo.neighbours},
                                  {"work_per_rank", work}};
    }
    std::printf("\n");
    if (row.contains("checkpoint")) {
      std::printf("%6s %10s", "", "at ckpt");
      for (const Partition how : {Partition::slabs, Partition::balanced, Partition::metis}) {
        const auto& r = row["checkpoint"][partition_name(how)];
        std::printf(" %7s %7.3f %8s", "", r["start_partition_substep_imbalance"].get<double>(), "");
      }
      std::printf("\n%6s %10s", "", "repart.");
      for (const Partition how : {Partition::slabs, Partition::balanced, Partition::metis}) {
        const auto& r = row["checkpoint"][partition_name(how)];
        std::printf(" %7s %7.3f %8ld", "", r["repartitioned_substep_imbalance"].get<double>(),
                    r["repartitioned_cut_bonds"].get<long>());
      }
      std::printf("\n");
    }
    table.push_back(row);
  }
  if (!rq.json_out.empty()) {
    std::ofstream out(rq.json_out);
    // Elements due at each kind of sub-step (levels f and finer): what the exchange after it moves.
    std::vector<long> level_elements(static_cast<std::size_t>(work_levels(start)), 0);
    for (int k : start.level)
      for (int f = 0; f <= k; ++f) ++level_elements[static_cast<std::size_t>(f)];
    out << nlohmann::json{{"case", rq.case_file},
                          {"elements", block.size()},
                          {"partition", partition_name(c.settings.partition)},
                          {"level_elements", level_elements},
                          {"table", table}}
               .dump(2)
        << "\n";
  }
  return 0;
}

}  // namespace

int balance_report(const BalanceRequest& rq) {
  if (rq.case_file.empty() || rq.ranks.empty())
    throw InputError("(command line)", "", "tessera balance CASE.yaml [--bodies CHECKPOINT.h5] --ranks 4,16,64");
  const Config config = Config::load(rq.case_file, rq.sets);
  const ConfigNode root = config.root();
  if (root.has("scene") && root.text("scene") == "blast") return blast_balance_report(rq, root);
  if (rq.bodies_file.empty())
    throw InputError("--bodies", "", "a DEM checkpoint whose bodies to spread (tessera balance CASE.yaml --bodies "
                     "CHECKPOINT.h5 --ranks 4,16,64)");
  const ConfigNode domain = root.section("domain");
  const Vec3 lo = domain.vec3("box_min", Dim::length), hi = domain.vec3("box_max", Dim::length);
  std::array<int, 3> requested{0, 0, 0};
  if (domain.has("process_grid")) {
    const auto g = domain.integers("process_grid", 3, 0, 1 << 20);
    for (int d = 0; d < 3; ++d) requested[d] = static_cast<int>(g[d]);
  }
  Vec3 spacing{};
  std::array<int, 3> cells{0, 0, 0};
  // The pressure multigrid's settings and the periodic directions: its levels' plan.
  std::array<std::array<BoundaryKind, 2>, 3> boundaries{};
  PoissonSettings poisson;
  if (const auto fluid = root.optional_section("fluid")) {
    const auto n = fluid->integers("cells", 3, 1, 1 << 24);
    for (int d = 0; d < 3; ++d) cells[d] = static_cast<int>(n[d]), spacing[d] = (hi[d] - lo[d]) / static_cast<double>(n[d]);
    boundaries = FlowSettings::boundaries_from_config(*fluid);
    poisson = FlowSettings::poisson_from_config(*fluid);
  }
  // A coupled run balances its flow cells (balance.cell_weight each) with its bodies' work times
  // the DEM sub-steps of a flow step (FlowScene::rank_work): the sub-steps come from the case.
  const bool coupled = root.has("scene") && root.text("scene") == "coupled";
  double substeps = 1, cell_weight = 0;
  if (coupled) {
    const auto coupling = root.optional_section("coupling");
    if (!coupling || !coupling->has("substeps"))
      throw InputError("coupling.substeps", "",
                       "the DEM sub-steps per flow step that weigh the bodies against the cells (a coupled run's "
                       "summary.json reports them): tessera balance CASE --set coupling.substeps=L ...");
    substeps = static_cast<double>(coupling->integer("substeps", 1, 1 << 30));
    cell_weight = 1;
    if (const auto b = root.optional_section("balance"))
      if (b->has("cell_weight")) cell_weight = b->real("cell_weight", Dim::none, Range::positive());
  }
  double skin = -1;
  if (const auto solid = root.optional_section("solid")) {
    if (const auto plane = solid->optional_section("plane")) {
      const std::string n = plane->choice("normal", {"x", "y", "z"});
      requested[n[0] - 'x'] = 1;
    }
    if (solid->has("neighbor_skin")) skin = solid->real("neighbor_skin", Dim::length, Range::positive());
  }

  // Bodies: the checkpoint's packed rows (ParticleStore::pack: radius in column 3, x in 6-8).
  const H5File f = H5File::open_read(rq.bodies_file, MPI_COMM_SELF);
  int cols = 0;
  const std::vector<double> rows = f.read_all<double>("bodies", cols);
  if (cols < 9) throw InputError("--bodies", rq.bodies_file, "a DEM checkpoint (its 'bodies' rows)");
  // A coupled run lays out each body's tetrahedra on the ranks its nodes reach: each shape's
  // farthest node (SolidPhase's reach), read from the case's shapes.
  std::vector<double> shape_reach;
  std::vector<ShapeTemplate> shapes;
  if (coupled) {
    const std::string case_dir = std::filesystem::absolute(std::filesystem::path(rq.case_file)).parent_path().string();
    shapes = read_shapes(root.section("solid"), case_dir);
    for (const ShapeTemplate& t : shapes) shape_reach.push_back(farthest_node(t));
  }
  // And their contact spheres where the bodies are (the pose in columns 15-18): the ghost elements
  // each rank's list bins (theory T5b).
  ElementPlaces elements;
  double element_radius = 0;
  std::vector<WorkSample> work;
  std::vector<Vec3> x;
  std::vector<double> radius, node_reach;
  std::vector<BodyPose> poses;  // a coupled case's, for its lay-outs (coupling/layout_cost.hpp)
  double r_max = 0, r_min = 1e300;
  for (std::size_t i = 0; i + static_cast<std::size_t>(cols) <= rows.size(); i += static_cast<std::size_t>(cols)) {
    x.push_back({rows[i + 6], rows[i + 7], rows[i + 8]});
    radius.push_back(rows[i + 3]);
    if (coupled) {  // shape k + 1 is the case's k-th (shape 0, a plain sphere, reaches its radius)
      const auto k = static_cast<std::size_t>(rows[i + 2]);
      if (k > shape_reach.size())
        throw InputError("--bodies", rq.bodies_file, "bodies of the case's shapes (one has shape " + std::to_string(k) + ")");
      node_reach.push_back(k == 0 ? rows[i + 3] : shape_reach[k - 1]);
      elements.first.push_back(elements.x.size());
      if (k == 0) {
        elements.x.push_back(x.back());
        elements.radius.push_back(rows[i + 3]);
        element_radius = std::max(element_radius, rows[i + 3]);
      } else if (cols >= 19) {
        const Quaternion q{rows[i + 15], rows[i + 16], rows[i + 17], rows[i + 18]};
        for (const Vec3& c : shapes[k - 1].spheres) {
          elements.x.push_back(x.back() + q.rotate(c));
          elements.radius.push_back(shapes[k - 1].sphere_radius);
        }
        poses.push_back({x.back(), q, int(k)});
        element_radius = std::max(element_radius, shapes[k - 1].sphere_radius);
      }
    }
    work.push_back({x.back(), 1.0});
    r_max = std::max(r_max, rows[i + 3]), r_min = std::min(r_min, rows[i + 3]);
  }
  if (work.empty()) throw InputError("--bodies", rq.bodies_file, "a checkpoint with bodies");
  if (skin < 0) skin = 0.5 * r_min;  // DemSettings' default
  elements.first.push_back(elements.x.size());
  elements.margin = r_max + element_radius + 3 * skin;  // DemSolver::list_elements
  const ElementPlaces* places = coupled && cols >= 19 ? &elements : nullptr;
  const double reach = 2 * r_max + skin;
  // The work a run's balance counts (DemSolver::work): 1 plus the listed pairs of each body.
  const std::vector<double> pairs_of = listed_pairs_per_body(x, radius, skin);
  for (std::size_t i = 0; i < work.size(); ++i) work[i].weight = (1 + pairs_of[i]) * substeps;
  // The cells each rank of a grid owns (their centres in its slab, as FluidGrid's ownership), times
  // their weight: the flow's share of a coupled rank's work.
  const double total_cells = double(cells[0]) * cells[1] * cells[2];
  auto cell_slabs = [&](std::array<int, 3> dims, const CutPlanes& interior) {
    std::array<std::vector<double>, 3> per_slab;
    for (int d = 0; d < 3; ++d) {
      per_slab[d].assign(static_cast<std::size_t>(dims[d]), 0.0);
      for (int i = 0; i < cells[d]; ++i) {
        const double x = lo[d] + (i + 0.5) * spacing[d];
        per_slab[d][static_cast<std::size_t>(std::upper_bound(interior[d].begin(), interior[d].end(), x) -
                                             interior[d].begin())] += 1;
      }
    }
    return per_slab;
  };
  auto cell_work = [&](std::array<int, 3> dims, const CutPlanes& interior) {
    const auto per_slab = cell_slabs(dims, interior);
    std::vector<double> w;
    for (int k = 0; k < dims[2]; ++k)
      for (int j = 0; j < dims[1]; ++j)
        for (int i = 0; i < dims[0]; ++i) w.push_back(per_slab[0][i] * per_slab[1][j] * per_slab[2][k] * cell_weight);
    return w;
  };
  // The pressure multigrid's levels on the cuts' blocks (fluid/multigrid_plan.hpp): per level its
  // cells, process grid, ghost layers, whether it was gathered, the ghost exchanges a V-cycle makes
  // on it (the operator's one on the finest), and along each split direction the largest face of a
  // block (its cells; 0 where the direction is not split) and the largest part a gathered level's
  // owner receives (cells) and how many parts an owner holds: what the scaling model prices per
  // message.
  auto multigrid_json = [&](std::array<int, 3> dims, const CutPlanes& interior) {
    const auto per_slab = cell_slabs(dims, interior);
    std::array<std::vector<int>, 3> blocks;
    std::array<bool, 3> periodic{};
    for (int d = 0; d < 3; ++d) {
      for (const double c : per_slab[d]) blocks[d].push_back(static_cast<int>(c));
      periodic[d] = boundaries[d][0] == BoundaryKind::periodic;
    }
    const auto& ps = poisson;
    const auto plan = plan_multigrid(blocks, periodic, 2, ps.level_pairs);
    const auto exchanges = multigrid_exchanges(plan, ps.pre_sweeps, ps.post_sweeps, ps.coarse_sweeps, ps.coarse_direct);
    nlohmann::json levels = nlohmann::json::array();
    for (std::size_t l = 0; l < plan.size(); ++l) {
      const MultigridLevelPlan& L = plan[l];
      const auto procs = L.procs();
      std::array<long, 3> face{};
      for (int d = 0; d < 3; ++d) {
        if (procs[d] < 2 && !periodic[d]) continue;
        const auto& a = L.blocks[(d + 1) % 3];
        const auto& b = L.blocks[(d + 2) % 3];
        face[d] = long(*std::max_element(a.begin(), a.end())) * long(*std::max_element(b.begin(), b.end()));
      }
      long largest_part = 0, parts_per_owner = 0;
      if (L.gathered()) {
        largest_part = parts_per_owner = 1;
        for (int d = 0; d < 3; ++d) {
          largest_part *= *std::max_element(L.parts[d].begin(), L.parts[d].end());
          parts_per_owner *= L.merged[d] ? 2 : 1;
        }
      }
      levels.push_back({{"cells", L.n}, {"procs", procs}, {"layers", L.layers}, {"halo", L.halo},
                        {"gathered", L.gathered()}, {"exchanges_per_cycle", exchanges[l]}, {"face_cells", face},
                        {"part_cells", largest_part}, {"parts_per_owner", parts_per_owner}});
    }
    return levels;
  };
  auto plus = [](std::vector<double> a, const std::vector<double>& b) {
    for (std::size_t r = 0; r < a.size(); ++r) a[r] += b[r];
    return a;
  };
  // What a rank does in a step for given cuts (solid/rank_load.hpp): the scaling model's input.
  auto load_json = [&](const RankLoad& l) {
    nlohmann::json j{{"bodies", l.bodies}, {"pairs", l.pairs}, {"ghosts", l.ghosts}, {"recv", l.recv},
                     {"total_pairs", l.total_pairs}, {"pair_imbalance", imbalance(l.pairs)}};
    if (!l.laid_out.empty()) j["laid_out"] = l.laid_out;
    if (!l.owned_elements.empty()) j["owned_elements"] = l.owned_elements, j["listed_ghost_elements"] = l.listed_ghost_elements;
    if (!l.list_tests.empty()) j["list_tests"] = l.list_tests;
    return j;
  };

  nlohmann::json table = nlohmann::json::array();
  std::printf("%zu bodies in [%g %g %g] - [%g %g %g] m; slabs at least %.4g m (2 r_max + skin)%s\n", work.size(), lo.x,
              lo.y, lo.z, hi.x, hi.y, hi.z, reach, spacing.x > 0 ? ", on the fluid's cell faces" : "");
  if (coupled) {
    double body_total = 0;
    for (const auto& w : work) body_total += w.weight;
    std::printf("coupled: %.0f cells x %g against the bodies' (1 + listed pairs) x %g sub-steps: %.4g and %.4g, %.1f %% "
                "bodies\n",
                total_cells, cell_weight, substeps, total_cells * cell_weight, body_total,
                100 * body_total / (body_total + total_cells * cell_weight));
  }
  // Imbalance of the work the cuts equalise (1 + listed pairs per body, as a run's balance counts)
  // and of the listed pairs each rank evaluates (a pair across a cut on both sides: the contact
  // work, solid/rank_load.hpp).
  std::printf("%6s %10s %24s %24s   balanced cuts (x | y | z)\n", "", "", "equal slabs", "balanced");
  std::printf("%6s %10s %11s %12s %11s %12s\n", "ranks", "grid", "work", "pairs", "work", "pairs");
  for (const int p : rq.ranks) {
    const auto dims = Decomposition::choose_dims(p, hi - lo, requested);
    Vec3 min_width;
    for (int d = 0; d < 3; ++d)  // a coupled run's: the halo's two cells, the reach plus a cell
      min_width[d] = coupled ? std::max(2 * spacing[d], reach + spacing[d]) : std::max(reach, spacing[d]);
    for (int d = 0; d < 3; ++d)
      if (dims[d] > 1 && dims[d] * min_width[d] > hi[d] - lo[d])
        throw InputError("--ranks", std::to_string(p),
                         "rank counts whose slabs are wider than the contact reach along axis " + std::to_string(d));
    std::vector<double> equal_work = rank_work(work, dims, equal_cuts(lo, hi, dims));
    // A coupled run's cut search (FlowScene::balance_if_due): its two stages, the cells (a box) and
    // the bodies, by histograms (staged_cuts); the others' exact quantiles of the bodies.
    const StagedCuts staged =
        coupled ? staged_cuts(MPI_COMM_SELF, {{{}, {WorkBox{lo, hi, total_cells * cell_weight}}}, {work, {}}}, lo, hi, dims,
                              min_width, spacing)
                : StagedCuts{balanced_cuts(work, lo, hi, dims, min_width, spacing), 0, "summed"};
    const CutPlanes& cuts = staged.cuts;
    std::vector<double> balanced_work = rank_work(work, dims, cuts);
    std::vector<double> equal_cells, balanced_cells;
    double equal = 0, balanced = 0;
    if (coupled) {  // the staged imbalance: the stages' busiest ranks over their means
      equal_cells = cell_work(dims, equal_cuts(lo, hi, dims));
      balanced_cells = cell_work(dims, cuts);
      equal = staged_imbalance({equal_cells, equal_work}), balanced = staged_imbalance({balanced_cells, balanced_work});
      equal_work = plus(equal_work, equal_cells);
      balanced_work = plus(balanced_work, balanced_cells);
    } else {
      equal = imbalance(equal_work), balanced = imbalance(balanced_work);
    }
    const RankLoad equal_load = dem_rank_load(x, radius, lo, hi, dims, equal_cuts(lo, hi, dims), skin, node_reach, places);
    const RankLoad balanced_load = dem_rank_load(x, radius, lo, hi, dims, cuts, skin, node_reach, places);
    // A coupled case's lay-outs, each rank's done and timed here (the body stages' price).
    auto layout_json = [&](const CutPlanes& c) {
      const LayoutCost lc = layout_cost(shapes, poses, lo, spacing, cells, cell_slabs(dims, c), 5);
      return nlohmann::json{{"seconds", lc.seconds}, {"cells", lc.cells}, {"bodies", lc.bodies}};
    };
    nlohmann::json layout_equal, layout_balanced;
    if (coupled && !poses.empty()) layout_equal = layout_json(equal_cuts(lo, hi, dims)), layout_balanced = layout_json(cuts);
    std::string text;
    for (int d = 0; d < 3; ++d) {
      if (d) text += " |";
      for (const double c : cuts[d]) text += " " + std::to_string(c);
    }
    std::printf("%6d %4dx%dx%-3d %11.3f %12.3f %11.3f %12.3f  %s\n", p, dims[0], dims[1], dims[2], equal,
                imbalance(equal_load.pairs), balanced, imbalance(balanced_load.pairs), text.c_str());
    table.push_back({{"ranks", p},
                     {"grid", dims},
                     {"imbalance_equal", equal},
                     {"imbalance_balanced", balanced},
                     {"cut_candidate", staged.candidate},  // coupled: which of staged_cuts' candidates
                     {"cuts", {cuts[0], cuts[1], cuts[2]}},
                     {"work_per_rank_equal", equal_work},  // rank order: x fastest; work = 1 + listed pairs per body
                                                            // (coupled: times the sub-steps, plus the cells')
                     {"work_per_rank_balanced", balanced_work},
                     {"load_equal", load_json(equal_load)},
                     {"load_balanced", load_json(balanced_load)}});
    if (!layout_balanced.is_null()) {
      table.back()["load_equal"]["layout"] = layout_equal;
      table.back()["load_balanced"]["layout"] = layout_balanced;
    }
    if (coupled) {  // the cells' share of the work above (cells x cell_weight per rank), and the
                    // cells of each slab along x, y, z (the halo's faces: the scaling model's)
      table.back()["cell_work_equal"] = equal_cells;
      table.back()["cell_work_balanced"] = balanced_cells;
      table.back()["cell_slabs_equal"] = cell_slabs(dims, equal_cuts(lo, hi, dims));
      table.back()["cell_slabs_balanced"] = cell_slabs(dims, cuts);
      table.back()["multigrid_equal"] = multigrid_json(dims, equal_cuts(lo, hi, dims));
      table.back()["multigrid_balanced"] = multigrid_json(dims, cuts);
    }
  }
  if (!rq.json_out.empty()) {
    std::ofstream out(rq.json_out);
    out << nlohmann::json{{"case", rq.case_file}, {"bodies", rq.bodies_file}, {"count", work.size()},
                          {"skin", skin},     {"r_max", r_max},           {"cells", total_cells},
                          {"cell_weight", cell_weight}, {"substeps", substeps}, {"table", table}}
               .dump(2)
        << "\n";
  }
  return 0;
}

}  // namespace tessera
