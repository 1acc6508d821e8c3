// SPDX-License-Identifier: MIT
// The blast scene (issue 17; docs/theory.md B1-B10): a block meshed into tetrahedra (Gmsh), bonded
// on every shared face, fractured by the gas pressure in a borehole. Case keys: section `blast`
// (mesh, density, bond, contact, borehole, stepping, time_step, stability_factor, travel_limit,
// max_level, damping, probe_time, process_grid, partition), `run`, `output`. Output:
// DIR/elements_NNNNNN.h5 + DIR/elements.xmf (each element's tetrahedron at its pose, with
// displacement, velocity, damage, broken faces and time-step level per cell), DIR/cracks.xmf (the
// released faces), checkpoints, summary.json.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <tuple>

#include "app/balance_record.hpp"
#include "app/blast_case.hpp"
#include "app/run_loop.hpp"
#include "app/scenes.hpp"
#include "core/balance.hpp"
#include "core/errors.hpp"
#include "core/h5_file.hpp"
#include "core/text_file.hpp"
#include "fracture/fracture_solver.hpp"

namespace tessera {

namespace fs = std::filesystem;

namespace {

FractureSettings read_fracture_settings(const ConfigNode& blast) {
  FractureSettings s;
  s.density = blast.real("density", Dim::density, Range::positive(), 2390.0);
  if (const auto b = blast.optional_section("bond")) {
    BondLaw& l = s.bond;
    l.kn = b->real("normal_stiffness", Dim::stiffness_per_area, Range::positive(), l.kn);
    l.ks = b->real("shear_stiffness", Dim::stiffness_per_area, Range::positive(), l.ks);
    l.cn = b->real("normal_damping", Dim::damping_per_area, Range::non_negative(), l.cn);
    l.cs = b->real("shear_damping", Dim::damping_per_area, Range::non_negative(), l.cs);
    l.cohesion = b->real("cohesion", Dim::pressure, Range::non_negative(), l.cohesion);
    l.friction = b->real("friction", Dim::none, Range::non_negative(), l.friction);
    l.tensile_strength = b->real("tensile_strength", Dim::pressure, Range::positive(), l.tensile_strength);
    l.fracture_energy = b->real("fracture_energy", Dim::energy_per_area, Range::positive(), l.fracture_energy);
  }
  if (const auto c = blast.optional_section("contact")) {
    s.contact_stiffness = c->real("stiffness", Dim::stiffness, Range::positive(), s.contact_stiffness);
    s.contact_damping = c->real("damping", Dim::damping, Range::non_negative(), s.contact_damping);
    s.contact_friction = c->real("friction", Dim::none, Range::non_negative(), s.contact_friction);
    s.sphere_divisions = static_cast<int>(c->integer("sphere_divisions", 3, 20, s.sphere_divisions));
    s.relax_born_overlaps = c->flag("relax_born_overlaps", s.relax_born_overlaps);  // B7b
  }
  if (blast.has("time_step")) s.time_step = blast.real("time_step", Dim::time, Range::positive());
  s.stability_factor = blast.real("stability_factor", Dim::none, Range::half_open(0, 1), s.stability_factor);
  s.damping = blast.flag("damping", true);
  s.implicit_damping = blast.flag("implicit_damping", false);
  s.damping_rtol = blast.real("damping_rtol", Dim::none, Range::positive(), s.damping_rtol);
  s.damping_theta = blast.real("damping_theta", Dim::none, Range::closed(0.5, 1), s.damping_theta);
  s.damping_frozen_angle = blast.real("damping_frozen_angle", Dim::none, Range::non_negative(), s.damping_frozen_angle);
  s.damping_interval = static_cast<int>(blast.integer("damping_interval", 1, 64, s.damping_interval));
  const std::string stepping = blast.choice("stepping", {"uniform", "travel", "stability"}, "uniform");
  s.stepping = stepping == "travel" ? Stepping::travel : (stepping == "stability" ? Stepping::stability : Stepping::uniform);
  s.travel_limit = blast.real("travel_limit", Dim::length, Range::positive(), s.travel_limit);
  s.max_level = static_cast<int>(blast.integer("max_level", 0, 40, s.max_level));
  s.partition = partition_from_name(blast.choice("partition", {"slabs", "balanced", "metis"}, "metis"));
  return s;
}

std::optional<Borehole> read_borehole(const ConfigNode& blast) {
  const auto h = blast.optional_section("borehole");
  if (!h) return std::nullopt;
  Borehole b;
  b.centre = h->vec3("centre", Dim::length);
  b.axis = h->vec3("axis", Dim::none, b.axis);
  if (norm(b.axis) == 0) h->fail("axis", "a non-zero direction");
  b.axis = b.axis / norm(b.axis);
  b.radius = h->real("radius", Dim::length, Range::positive());
  b.p0 = h->real("peak_pressure", Dim::pressure, Range::non_negative(), b.p0);
  b.rise = h->real("rise_time", Dim::time, Range::positive(), b.rise);
  b.fall = h->real("fall_ratio", Dim::none, Range::positive(), b.fall);
  return b;
}

// The mesh's bounding box, a little enlarged, is the process grid's box.
std::pair<Vec3, Vec3> bounding_box(const TetMesh& m) {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const Vec3& p : m.nodes)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d]);
  const Vec3 pad = (hi - lo) * 1e-3;
  return {lo - pad, hi + pad};
}

}  // namespace

BlastCase read_blast_case(const ConfigNode& root, const std::string& case_dir) {
  BlastCase c;
  const ConfigNode blast = root.section("blast");
  const fs::path mesh_path(blast.text("mesh"));
  c.mesh_file = mesh_path.is_absolute() ? mesh_path.string() : (fs::path(case_dir) / mesh_path).lexically_normal().string();
  c.mesh = read_gmsh(c.mesh_file);
  c.settings = read_fracture_settings(blast);
  c.hole = read_borehole(blast);
  if (blast.has("process_grid")) {
    const auto g = blast.integers("process_grid", 3, 0, 1 << 20);
    c.grid = {int(g[0]), int(g[1]), int(g[2])};
  }
  std::tie(c.lo, c.hi) = bounding_box(c.mesh);
  return c;
}

namespace {

class BlastScene final : public SteppedScene {
 public:
  BlastScene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir) {
    BlastCase c = read_blast_case(root, case_dir);
    mesh_file_ = c.mesh_file;
    probe_time_ = root.section("blast").real("probe_time", Dim::time, Range::positive(), 5e-4);
    decomp_ = std::make_unique<Decomposition>(comm, c.lo, c.hi, c.grid);
    solver_ = std::make_unique<FractureSolver>(*decomp_, build_bonded_block(c.mesh, c.settings.density), c.settings, c.hole);
    balance_.read(root);
    if (balance_.measure_time)
      throw InputError("balance.measure", "time", "counts (the blast's work is counted from its levels and pairs)");
    const auto& hole = c.hole;
    read_loop_keys(root, true);
    // The probe: the element whose initial centroid is nearest the hole's axis (lowest index on a tie).
    if (hole) {
      double best = 1e300;
      for (std::size_t e = 0; e < solver_->block().size(); ++e) {
        const Vec3 d = solver_->block().x0[e] - hole->centre;
        const double r = norm(d - hole->axis * dot(d, hole->axis));
        if (r < best) best = r, probe_ = static_cast<long>(e);
      }
    }
  }
  const char* name() const override { return "blast"; }

 protected:
  const Decomposition& decomposition() const override { return *decomp_; }
  double time() const override { return solver_->time(); }
  long steps() const override { return solver_->steps(); }
  double last_dt() const override { return solver_->steps() > 0 ? solver_->dt() : 0; }
  PhaseTimers& phase_timers() override { return solver_->timers(); }

  void start(const RunOptions& opt) override {
    if (opt.restart) read_checkpoint(*opt.restart);
    solver_->setup(!opt.restart);
    out_dir_ = opt.output_dir;
  }

  void begin_output(const RunOptions& opt) override {
    if (decomp_->rank() == 0 && !opt.quiet) {
      const BondedBlock& b = solver_->block();
      std::printf("blast: %zu elements, %zu bonds, %zu hole faces, dt %.3g s, %d ranks\n", b.size(), b.bonds.size(),
                  solver_->hole_faces().size(), solver_->dt(), decomp_->size());
      std::fflush(stdout);
    }
    write_snapshot();
  }

  void step(const RunOptions&) override {
    solver_->step();
    if (!probed_ && probe_ >= 0 && solver_->time() >= probe_time_ - 0.5 * solver_->dt()) {
      const auto e = static_cast<std::size_t>(probe_);
      probe_displacement_ = norm(solver_->x()[e] - solver_->block().x0[e]);
      probed_ = true;
    }
  }

  bool after_step(const RunOptions&) override {
    // Issue 19: every balance.interval macro steps, the work now (levels, intact bonds, listed
    // pairs) over the owners; past the threshold, a new partition (FractureSolver::rebalance).
    if (balance_.due(solver_->steps(), decomp_->size())) {
      const FractureSolver::BalanceCheck check = solver_->balance_check();
      if (balance_.over_threshold(check.imbalance))
        balance_.rebalanced(solver_->steps(), check.imbalance, solver_->rebalance(check));
    }
    if (solver_->steps() % 1000 == 0) {
      // Blow-up check (positions are replicated: every rank decides alike).
      for (const Vec3& x : solver_->x())
        if (!std::isfinite(x.x + x.y + x.z))
          throw CollectiveRunError("blast: an element's position is not finite at step " +
                                   std::to_string(solver_->steps()) + "; lower blast.stability_factor");
    }
    return false;
  }

  std::string progress() override {
    char line[160];
    std::snprintf(line, sizeof line, "broken faces %ld  contact pairs %zu  P %.3g MPa", solver_->broken_count(),
                  solver_->pair_count(), solver_->borehole() ? solver_->borehole()->pressure(time()) / 1e6 : 0.0);
    return line;
  }

  void write_snapshot() override;
  void write_checkpoint(const std::string& path) override;
  void summarise(nlohmann::json& s) override;

 private:
  void read_checkpoint(const std::string& path);
  std::vector<double> element_damage() const;

  std::unique_ptr<Decomposition> decomp_;
  std::unique_ptr<FractureSolver> solver_;
  BalanceRecord balance_;
  std::string mesh_file_, out_dir_;
  double probe_time_ = 5e-4, probe_displacement_ = 0;
  long probe_ = -1;
  bool probed_ = false;
  struct Snapshot {
    double time;
    std::string file;
    long cracks = 0;  // released faces
  };
  std::vector<Snapshot> snapshots_;
};

std::vector<double> BlastScene::element_damage() const {
  const BondedBlock& b = solver_->block();
  std::vector<double> damage(b.size(), 0.0);
  for (std::size_t k = 0; k < b.bonds.size(); ++k) {
    double d = 0;
    if (solver_->broken()[k]) {
      d = 1;
    } else {
      for (const BondVertex& s : solver_->bond_state()[k]) d = std::max(d, bond_damage(solver_->settings().bond, s));
    }
    for (int e : {b.bonds[k].master, b.bonds[k].slave})
      damage[static_cast<std::size_t>(e)] = std::max(damage[static_cast<std::size_t>(e)], d);
  }
  return damage;
}

void BlastScene::write_snapshot() {
  if (!snapshots_.empty() && snapshots_.back().time == time()) return;
  solver_->sync_state();
  MPI_Comm comm = decomp_->comm();
  const bool root = decomp_->rank() == 0;
  const BondedBlock& b = solver_->block();
  const std::size_t n = root ? b.size() : 0;
  long cracks = 0;
  char name[64];
  std::snprintf(name, sizeof name, "elements_%06zu.h5", snapshots_.size());
  if (root) fs::create_directories(out_dir_);
  MPI_Barrier(comm);
  {
    H5File f = H5File::create(out_dir_ + "/" + name, comm);
    std::vector<double> nodes, disp, vel, broken_faces(n, 0.0), level(n, 0.0), mesh_element(n);
    for (std::size_t e = 0; e < n; ++e) level[e] = solver_->levels().empty() ? 0.0 : solver_->levels()[e];
    for (std::size_t e = 0; e < n; ++e) mesh_element[e] = b.mesh_index[e];  // the element in the mesh file
    std::vector<std::int64_t> tets;
    for (std::size_t e = 0; e < n; ++e) {
      for (int k = 0; k < 4; ++k) {
        const Vec3 p = solver_->x()[e] + solver_->q()[e].rotate(b.vertices[e][k]);
        nodes.insert(nodes.end(), {p.x, p.y, p.z});
        tets.push_back(static_cast<std::int64_t>(4 * e + static_cast<std::size_t>(k)));
      }
      const Vec3 d = solver_->x()[e] - b.x0[e], v = solver_->v()[e];
      disp.insert(disp.end(), {d.x, d.y, d.z});
      vel.insert(vel.end(), {v.x, v.y, v.z});
    }
    for (std::size_t k = 0; root && k < b.bonds.size(); ++k)
      if (solver_->broken()[k])
        broken_faces[static_cast<std::size_t>(b.bonds[k].master)] += 1, broken_faces[static_cast<std::size_t>(b.bonds[k].slave)] += 1;
    std::vector<double> damage = root ? element_damage() : std::vector<double>{};
    f.write_rows("nodes", nodes.data(), 4 * n, 3);
    f.write_rows("tetrahedra", tets.data(), n, 4);
    f.write_rows("displacement", disp.data(), n, 3);
    f.write_rows("velocity", vel.data(), n, 3);
    f.write_rows("damage", damage.data(), n, 1);
    f.write_rows("broken_faces", broken_faces.data(), n, 1);
    f.write_rows("dt_level", level.data(), n, 1);
    f.write_rows("mesh_element", mesh_element.data(), n, 1);
    // The released faces, as the master element holds them now: ParaView's crack surfaces.
    std::vector<double> crack_nodes;
    std::vector<std::int64_t> crack_tris;
    for (std::size_t k = 0; root && k < b.bonds.size(); ++k) {
      if (!solver_->broken()[k]) continue;
      const BondGeometry& g = b.bonds[k];
      const std::size_t m = static_cast<std::size_t>(g.master);
      for (int j = 0; j < 3; ++j) {
        const Vec3 p = solver_->x()[m] + solver_->q()[m].rotate(g.at_master[j]);
        crack_tris.push_back(static_cast<std::int64_t>(crack_nodes.size() / 3));
        crack_nodes.insert(crack_nodes.end(), {p.x, p.y, p.z});
      }
    }
    cracks = static_cast<long>(crack_tris.size() / 3);
    f.write_rows("crack_nodes", crack_nodes.data(), crack_nodes.size() / 3, 3);
    f.write_rows("crack_triangles", crack_tris.data(), crack_tris.size() / 3, 3);
    f.set_attribute("time", time());
  }
  snapshots_.push_back({time(), name, cracks});
  if (!root) return;
  const long N = static_cast<long>(b.size());
  std::ostringstream grids;
  grids << std::setprecision(17);
  for (const Snapshot& s : snapshots_) {
    auto item = [&](const char* ds, const char* type, int cols, long rows) {
      std::ostringstream o;
      o << "<DataItem Format=\"HDF\" NumberType=\"" << type << "\" Precision=\"8\" Dimensions=\"" << rows
        << (cols > 1 ? " " + std::to_string(cols) : "") << "\">" << s.file << ":/" << ds << "</DataItem>";
      return o.str();
    };
    grids << "   <Grid Name=\"elements\" GridType=\"Uniform\">\n    <Time Value=\"" << s.time << "\"/>\n"
          << "    <Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"" << N << "\">"
          << item("tetrahedra", "Int", 4, N) << "</Topology>\n"
          << "    <Geometry GeometryType=\"XYZ\">" << item("nodes", "Float", 3, 4 * N) << "</Geometry>\n";
    for (const char* v : {"displacement", "velocity"})
      grids << "    <Attribute Name=\"" << v << "\" AttributeType=\"Vector\" Center=\"Cell\">"
            << item(v, "Float", 3, N) << "</Attribute>\n";
    for (const char* v : {"damage", "broken_faces", "dt_level", "mesh_element"})
      grids << "    <Attribute Name=\"" << v << "\" AttributeType=\"Scalar\" Center=\"Cell\">"
            << item(v, "Float", 1, N) << "</Attribute>\n";
    grids << "   </Grid>\n";
  }
  std::ostringstream crack_grids;
  crack_grids << std::setprecision(17);
  for (const Snapshot& s : snapshots_) {
    // ParaView's reader wants a grid at every time: an empty one is a single degenerate triangle.
    crack_grids << "   <Grid Name=\"cracks\" GridType=\"Uniform\">\n    <Time Value=\"" << s.time << "\"/>\n";
    if (s.cracks > 0) {
      crack_grids << "    <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << s.cracks << "\"><DataItem Format=\"HDF\" "
                  << "NumberType=\"Int\" Precision=\"8\" Dimensions=\"" << s.cracks << " 3\">" << s.file
                  << ":/crack_triangles</DataItem></Topology>\n    <Geometry GeometryType=\"XYZ\"><DataItem Format=\"HDF\" "
                  << "NumberType=\"Float\" Precision=\"8\" Dimensions=\"" << 3 * s.cracks << " 3\">" << s.file
                  << ":/crack_nodes</DataItem></Geometry>\n";
    } else {
      crack_grids << "    <Topology TopologyType=\"Triangle\" NumberOfElements=\"1\"><DataItem Format=\"XML\" "
                  << "NumberType=\"Int\" Dimensions=\"1 3\">0 0 0</DataItem></Topology>\n    <Geometry "
                  << "GeometryType=\"XYZ\"><DataItem Format=\"XML\" NumberType=\"Float\" Dimensions=\"1 3\">0 0 0"
                  << "</DataItem></Geometry>\n";
    }
    crack_grids << "   </Grid>\n";
  }
  write_file_atomically(out_dir_ + "/cracks.xmf",
                        "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n  <Grid Name=\"cracks\" "
                        "GridType=\"Collection\" CollectionType=\"Temporal\">\n" +
                            crack_grids.str() + "  </Grid>\n </Domain>\n</Xdmf>\n");
  write_file_atomically(out_dir_ + "/elements.xmf",
                        "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n  <Grid Name=\"blast\" "
                        "GridType=\"Collection\" CollectionType=\"Temporal\">\n" +
                            grids.str() + "  </Grid>\n </Domain>\n</Xdmf>\n");
}

void BlastScene::write_checkpoint(const std::string& path) {
  solver_->sync_state();
  MPI_Comm comm = decomp_->comm();
  const bool root = decomp_->rank() == 0;
  const BondedBlock& b = solver_->block();
  const std::size_t n = root ? b.size() : 0, nb = root ? b.bonds.size() : 0;
  std::vector<double> state, bonds;
  for (std::size_t e = 0; e < n; ++e) {
    const Vec3 &x = solver_->x()[e], &v = solver_->v()[e], &L = solver_->angular_momentum()[e];
    const Quaternion& q = solver_->q()[e];
    const Vec3 &F = solver_->force()[e], &T = solver_->torque()[e];
    state.insert(state.end(), {x.x, x.y, x.z, q.w, q.x, q.y, q.z, v.x, v.y, v.z, L.x, L.y, L.z, F.x, F.y, F.z, T.x,
                               T.y, T.z});
  }
  for (std::size_t k = 0; k < nb; ++k) {
    for (const BondVertex& s : solver_->bond_state()[k]) bonds.insert(bonds.end(), {s.slip[0], s.slip[1], s.u_max});
    bonds.push_back(solver_->broken()[k]);
  }
  const ContactListState list = solver_->contact_list_state();
  std::vector<double> list_poses;
  for (std::size_t e = 0; e < (list.stale ? 0 : n); ++e) {
    const Vec3& x = list.x[e];
    const Quaternion& q = list.q[e];
    list_poses.insert(list_poses.end(), {x.x, x.y, x.z, q.w, q.x, q.y, q.z});
  }
  std::vector<double> frozen;
  const std::vector<Quaternion> fq = solver_->damping_frozen();
  for (std::size_t e = 0; e < n; ++e) frozen.insert(frozen.end(), {fq[e].w, fq[e].x, fq[e].y, fq[e].z});
  const std::string tmp = path + ".tmp";
  {
    H5File f = H5File::create(tmp, comm);
    f.write_rows("elements", state.data(), n, 19);
    f.write_rows("contact_list_poses", list_poses.data(), list_poses.size() / 7, 7);
    f.write_rows("damping_frozen", frozen.data(), n, 4);  // B9b: the damping matrix's orientations
    std::vector<std::int64_t> pairs, unlisted;
    for (const auto& [a, b] : list.pairs) pairs.insert(pairs.end(), {a, b});
    for (int u : list.unlisted) unlisted.push_back(u);
    f.write_rows("contact_list_pairs", pairs.data(), root ? pairs.size() / 2 : 0, 2);
    f.write_rows("contact_list_unlisted", unlisted.data(), root ? unlisted.size() : 0, 1);
    f.set_attribute("contact_list_cell_radius", list.cell_radius);
    std::vector<std::int64_t> sunk_keys;  // B7b: the pairs born overlapping and their depths now
    std::vector<double> sunk_depths;
    for (const auto& [k, d] : list.sunk) sunk_keys.insert(sunk_keys.end(), {k.first, k.second}), sunk_depths.push_back(d);
    f.write_rows("contact_sunk_keys", sunk_keys.data(), root ? sunk_depths.size() : 0, 2);
    f.write_rows("contact_sunk_depths", sunk_depths.data(), root ? sunk_depths.size() : 0, 1);
    f.set_attribute("born_overlaps", static_cast<long>(list.born_overlaps));
    f.set_attribute("deepest_born_overlap", list.deepest_born_overlap);
    f.write_rows("bonds", bonds.data(), nb, 10);
    std::vector<std::int64_t> order(b.mesh_index.begin(), b.mesh_index.begin() + static_cast<std::ptrdiff_t>(n));
    f.write_rows("mesh_index", order.data(), n, 1);  // the element order the rows follow
    f.set_attribute("time", time());
    f.set_attribute("steps", steps());
    f.set_attribute("probe_displacement", probe_displacement_);
    f.set_attribute("probed", static_cast<long>(probed_));
    f.set_attribute("mesh", mesh_file_);
  }
  MPI_Barrier(comm);
  if (root) fs::rename(tmp, path);
  MPI_Barrier(comm);
}

void BlastScene::read_checkpoint(const std::string& path) {
  const BlastCheckpoint c = read_blast_checkpoint(path, decomp_->comm(), *solver_);
  probe_displacement_ = c.probe_displacement;
  probed_ = c.probed;
}

}  // namespace

BlastCheckpoint read_blast_checkpoint(const std::string& path, MPI_Comm comm, FractureSolver& solver) {
  const H5File f = H5File::open_read(path, comm);
  int cols = 0;
  const std::vector<double> state = f.read_all<double>("elements", cols);
  const BondedBlock& b = solver.block();
  if (cols != 19 || state.size() != 19 * b.size())
    throw InputError("restart", path, "a checkpoint of this case's mesh (" + std::to_string(b.size()) + " elements)");
  const std::vector<double> bonds = f.read_all<double>("bonds", cols);
  if (cols != 10 || bonds.size() != 10 * b.bonds.size())
    throw InputError("restart", path, "a checkpoint of this case's mesh (" + std::to_string(b.bonds.size()) + " bonds)");
  // The rows follow the block's element order (Morton since 2026-11-30): a checkpoint written in
  // another order would put every state on the wrong element.
  const std::vector<std::int64_t> order = f.has("mesh_index") ? f.read_all<std::int64_t>("mesh_index", cols)
                                                               : std::vector<std::int64_t>{};
  if (!std::equal(order.begin(), order.end(), b.mesh_index.begin(), b.mesh_index.end()))
    throw InputError("restart", path,
                     "a checkpoint whose elements are in this build's order (Morton order of the centroids; "
                     "this one was written by a build before 2026-11-30 or from another mesh)");
  std::vector<Vec3> x(b.size()), v(b.size()), L(b.size()), F(b.size()), T(b.size());
  std::vector<Quaternion> q(b.size());
  for (std::size_t e = 0; e < b.size(); ++e) {
    const double* s = &state[19 * e];
    x[e] = {s[0], s[1], s[2]}, q[e] = {s[3], s[4], s[5], s[6]}, v[e] = {s[7], s[8], s[9]}, L[e] = {s[10], s[11], s[12]};
    F[e] = {s[13], s[14], s[15]}, T[e] = {s[16], s[17], s[18]};
  }
  std::vector<std::array<BondVertex, 3>> bs(b.bonds.size());
  std::vector<char> broken(b.bonds.size());
  for (std::size_t k = 0; k < b.bonds.size(); ++k) {
    const double* s = &bonds[10 * k];
    for (std::size_t j = 0; j < 3; ++j) bs[k][j].slip[0] = s[3 * j], bs[k][j].slip[1] = s[3 * j + 1], bs[k][j].u_max = s[3 * j + 2];
    broken[k] = s[9] != 0;
  }
  ContactListState list;
  if (f.has("contact_list_poses")) {
    const std::vector<double> poses = f.read_all<double>("contact_list_poses", cols);
    if (cols == 7 && poses.size() == 7 * b.size()) {
      list.stale = false;
      for (std::size_t e = 0; e < b.size(); ++e) {
        const double* s = &poses[7 * e];
        list.x.push_back({s[0], s[1], s[2]});
        list.q.push_back({s[3], s[4], s[5], s[6]});
      }
      const std::vector<std::int64_t> pairs = f.read_all<std::int64_t>("contact_list_pairs", cols);
      for (std::size_t k = 0; k + 1 < pairs.size(); k += 2) list.pairs.push_back({pairs[k], pairs[k + 1]});
      for (const std::int64_t u : f.read_all<std::int64_t>("contact_list_unlisted", cols)) list.unlisted.push_back(static_cast<int>(u));
      list.cell_radius = f.attribute_double("contact_list_cell_radius");
    }
  }
  if (f.has("contact_sunk_keys")) {  // B7b (checkpoints from before 2026-12-02 have none)
    const std::vector<std::int64_t> keys = f.read_all<std::int64_t>("contact_sunk_keys", cols);
    const std::vector<double> depths = f.read_all<double>("contact_sunk_depths", cols);
    for (std::size_t k = 0; k < depths.size(); ++k) list.sunk.push_back({{keys[2 * k], keys[2 * k + 1]}, depths[k]});
    list.born_overlaps = f.attribute_long("born_overlaps");
    list.deepest_born_overlap = f.attribute_double("deepest_born_overlap");
  }
  solver.restore(x, q, v, L, bs, broken, list, F, T);
  if (f.has("damping_frozen")) {  // B9b (since 2026-12-07; before, the orientations themselves)
    const std::vector<double> fr = f.read_all<double>("damping_frozen", cols);
    if (cols != 4 || fr.size() != 4 * b.size()) throw InputError("restart", path, "4 numbers per element in damping_frozen");
    std::vector<Quaternion> frozen(b.size());
    for (std::size_t e = 0; e < b.size(); ++e) frozen[e] = {fr[4 * e], fr[4 * e + 1], fr[4 * e + 2], fr[4 * e + 3]};
    solver.set_damping_frozen(frozen);
  }
  solver.set_clock(f.attribute_double("time"), f.attribute_long("steps"));
  return {f.attribute_double("probe_displacement"), f.attribute_long("probed") != 0};
}

namespace {

void BlastScene::summarise(nlohmann::json& s) {
  solver_->sync_state();
  const FractureEnergies en = solver_->energies();
  const BondedBlock& b = solver_->block();
  double crack_area = 0;
  for (std::size_t k = 0; k < b.bonds.size(); ++k)
    if (solver_->broken()[k]) crack_area += b.bonds[k].area;
  long counts[3] = {solver_->element_steps(), solver_->bond_evaluations(), solver_->contact_evaluations()};
  // Every rank's counters (the measured work per rank, issue 19), then their sums.
  std::vector<long> each(3 * static_cast<std::size_t>(decomp_->size()));
  MPI_Allgather(counts, 3, MPI_LONG, each.data(), 3, MPI_LONG, decomp_->comm());
  MPI_Allreduce(MPI_IN_PLACE, counts, 3, MPI_LONG, MPI_SUM, decomp_->comm());
  // Per-rank time in contact work (bonds and sphere contacts), every rank's.
  const double mine = solver_->timers().total("bond_forces") + solver_->timers().total("contact_forces");
  std::vector<double> contact_time(static_cast<std::size_t>(decomp_->size()));
  MPI_Allgather(&mine, 1, MPI_DOUBLE, contact_time.data(), 1, MPI_DOUBLE, decomp_->comm());
  nlohmann::json q;
  q["elements"] = b.size();
  q["bonds"] = b.bonds.size();
  q["broken_faces"] = solver_->broken_count();
  q["crack_area"] = crack_area;
  // Quasi-2D: the broken faces' area over the block's depth along the hole's axis.
  if (solver_->borehole()) {
    double lo = 1e300, hi = -1e300;
    for (const Vec3& p : b.nodes) {
      const double z = dot(p, solver_->borehole()->axis);
      lo = std::min(lo, z), hi = std::max(hi, z);
    }
    q["crack_length"] = crack_area / (hi - lo);
  }
  // B8a: the bonded fragments, the hole faces the gas no longer pushes, and the fastest element.
  q["fragments"] = solver_->fragments().count();
  if (solver_->borehole()) q["unloaded_hole_faces"] = solver_->unloaded_hole_faces();
  double fastest = 0;
  for (std::size_t e = 0; e < b.size(); ++e)
    if (solver_->owns(e)) fastest = std::max(fastest, norm(solver_->v()[e]));
  MPI_Allreduce(MPI_IN_PLACE, &fastest, 1, MPI_DOUBLE, MPI_MAX, decomp_->comm());
  q["max_speed"] = fastest;
  q["born_overlaps"] = solver_->born_overlaps();  // B7b
  q["deepest_born_overlap"] = solver_->deepest_born_overlap();
  q["sunk_pairs"] = solver_->sunk_pairs();
  q["kinetic_energy"] = en.kinetic;
  q["bond_elastic_energy"] = en.bond_elastic;
  q["contact_elastic_energy"] = en.contact_elastic;
  if (probe_ >= 0) {
    q["probe_element"] = probe_;
    q["probe_time"] = probe_time_;
    if (probed_) q["probe_displacement"] = probe_displacement_;
  }
  s["quantities"] = q;
  s["dt"] = solver_->dt();
  if (solver_->settings().stepping != Stepping::uniform) {
    s["smallest_dt"] = solver_->min_dt();
    s["smallest_dt_time"] = solver_->min_dt_time();
  }
  s["element_steps"] = counts[0];
  s["bond_evaluations"] = counts[1];
  s["contact_evaluations"] = counts[2];
  if (solver_->settings().implicit_damping) {  // B9a: the dashpots' solves (the same on every rank)
    s["damping_solves"] = solver_->damping_solves();
    s["damping_iterations"] = solver_->damping_iterations();
  }
  s["contact_spheres"] = solver_->sphere_count();
  s["contact_list_builds"] = solver_->list_builds();
  s["contact_list_refreshes"] = solver_->list_refreshes();
  s["contact_seconds_per_rank"] = contact_time;
  // The partition (issue 19): the planned work per rank on the last partition (the start's unless
  // the run rebalanced) and its imbalance, the bonds cut.
  const std::vector<double> planned = solver_->planned_work();
  nlohmann::json measured;
  const char* names[3] = {"element_steps", "bond_evaluations", "contact_evaluations"};
  for (std::size_t k = 0; k < 3; ++k) {
    std::vector<long> v;
    for (int r = 0; r < decomp_->size(); ++r) v.push_back(each[3 * static_cast<std::size_t>(r) + k]);
    measured[names[k]] = v;
  }
  // The measured work in the partition's units: updates plus bond evaluations at their cost.
  std::vector<double> measured_work;
  for (int r = 0; r < decomp_->size(); ++r)
    measured_work.push_back(static_cast<double>(each[3 * static_cast<std::size_t>(r)]) +
                            kBondCostPerUpdate * static_cast<double>(each[3 * static_cast<std::size_t>(r) + 1]));
  s["partition"] = {{"method", partition_name(solver_->settings().partition)},
                    {"measured_per_rank", measured},
                    {"measured_imbalance", imbalance(measured_work)},
                    {"planned_work_per_rank", planned},
                    {"planned_imbalance", imbalance(planned)},
                    {"planned_substep_imbalance", substep_imbalance(solver_->planned_level_work())},
                    {"planned_level_imbalance", level_imbalance(solver_->planned_level_work())},
                    {"cut_bonds", solver_->cut_bond_count()}};
  if (balance_.enabled) s["balance"] = balance_.summary();
  s["output"] = {{"checkpoint", "checkpoint.h5"},
                 {"snapshots", snapshots_.empty() ? "" : "elements.xmf, cracks.xmf"}};
}

}  // namespace

std::unique_ptr<Scene> make_blast_scene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir) {
  return std::make_unique<BlastScene>(root, comm, case_dir);
}

}  // namespace tessera
