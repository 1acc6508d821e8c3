// SPDX-License-Identifier: MIT
#include "solid/dem_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <tuple>

#include "core/errors.hpp"
#include "core/h5_file.hpp"
#include "core/text_file.hpp"

namespace tessera {

namespace fs = std::filesystem;

constexpr int kMeshStateSize = 16;        // origin, q, velocity, omega, theta, theta', theta''
constexpr int kFreeSphereStateSize = 15;  // x, v, omega, force, torque

namespace {

int comm_rank(MPI_Comm c) {
  int r = 0;
  MPI_Comm_rank(c, &r);
  return r;
}

// One snapshot's bodies: a Polyvertex grid (file: the HDF5 path as the index sees it).
std::string bodies_grid(double time, const std::string& file, long n, bool loads) {
  std::ostringstream o;
  o << std::setprecision(17);
  auto item = [&](const std::string& ds, int cols) {
    std::ostringstream s;
    s << "<DataItem Format=\"HDF\" NumberType=\"" << (ds == "id" ? "Int\" Precision=\"8" : "Float\" Precision=\"8")
      << "\" Dimensions=\"" << n << (cols > 1 ? " " + std::to_string(cols) : "") << "\">" << file << ":/" << ds
      << "</DataItem>";
    return s.str();
  };
  o << "   <Grid Name=\"bodies\" GridType=\"Uniform\">\n"
    << "    <Time Value=\"" << time << "\"/>\n"
    << "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n << "\"/>\n"
    << "    <Geometry GeometryType=\"XYZ\">" << item("position", 3) << "</Geometry>\n"
    << "    <Attribute Name=\"velocity\" AttributeType=\"Vector\" Center=\"Node\">" << item("velocity", 3)
    << "</Attribute>\n"
    << "    <Attribute Name=\"angular_velocity\" AttributeType=\"Vector\" Center=\"Node\">"
    << item("angular_velocity", 3) << "</Attribute>\n"
    << "    <Attribute Name=\"orientation\" AttributeType=\"Matrix\" Center=\"Node\">" << item("orientation", 4)
    << "</Attribute>\n"
    << "    <Attribute Name=\"radius\" AttributeType=\"Scalar\" Center=\"Node\">" << item("radius", 1)
    << "</Attribute>\n"
    << "    <Attribute Name=\"id\" AttributeType=\"Scalar\" Center=\"Node\">" << item("id", 1) << "</Attribute>\n"
    << "    <Attribute Name=\"shape\" AttributeType=\"Scalar\" Center=\"Node\">" << item("shape", 1)
    << "</Attribute>\n";
  if (loads)
    o << "    <Attribute Name=\"external_force\" AttributeType=\"Vector\" Center=\"Node\">"
      << item("external_force", 3) << "</Attribute>\n"
      << "    <Attribute Name=\"external_torque\" AttributeType=\"Vector\" Center=\"Node\">"
      << item("external_torque", 3) << "</Attribute>\n";
  o << "   </Grid>\n";
  return o.str();
}

// One snapshot's grain surfaces: an unstructured triangle grid.
std::string grains_grid(double time, const std::string& file, long nodes, long tris) {
  std::ostringstream o;
  o << std::setprecision(17);
  o << "   <Grid Name=\"grains\" GridType=\"Uniform\">\n"
    << "    <Time Value=\"" << time << "\"/>\n"
    << "    <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << tris << "\">"
    << "<DataItem Format=\"HDF\" NumberType=\"Int\" Precision=\"8\" Dimensions=\"" << tris << " 3\">" << file
    << ":/surface_triangles</DataItem></Topology>\n"
    << "    <Geometry GeometryType=\"XYZ\"><DataItem Format=\"HDF\" NumberType=\"Float\" Precision=\"8\" "
    << "Dimensions=\"" << nodes << " 3\">" << file << ":/surface_nodes</DataItem></Geometry>\n"
    << "    <Attribute Name=\"velocity\" AttributeType=\"Vector\" Center=\"Node\"><DataItem Format=\"HDF\" "
    << "NumberType=\"Float\" Precision=\"8\" Dimensions=\"" << nodes << " 3\">" << file
    << ":/surface_velocity</DataItem></Attribute>\n"
    << "    <Attribute Name=\"id\" AttributeType=\"Scalar\" Center=\"Cell\"><DataItem Format=\"HDF\" "
    << "NumberType=\"Int\" Precision=\"8\" Dimensions=\"" << tris << "\">" << file
    << ":/surface_id</DataItem></Attribute>\n"
    << "   </Grid>\n";
  return o.str();
}

std::string temporal_index(const char* name, const std::string& grids) {
  return std::string("<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n  <Grid Name=\"") + name +
         "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n" + grids + "  </Grid>\n </Domain>\n</Xdmf>\n";
}

}  // namespace

void SnapshotSeries::write(DemSolver& dem) {
  dem.complete_step();
  // One snapshot per time: a run ending on a snapshot time does not write the same state twice
  // (two grids at one time make ParaView's XDMF reader return an empty multiblock).
  if (!entries_.empty() && entries_.back().time == dem.time()) return;
  MPI_Comm comm = dem.decomposition().comm();
  const ParticleStore& p = dem.particles();
  char name[64];
  std::snprintf(name, sizeof name, "particles_%06zu.h5", entries_.size());
  if (comm_rank(comm) == 0) fs::create_directories(dir_);
  MPI_Barrier(comm);
  long n = 0, surface_nodes = 0, surface_triangles = 0;
  {
    H5File f = H5File::create(dir_ + "/" + name, comm);
    const std::size_t m = p.owned;
    n = f.write_rows("position", p.x.data(), m, 3);
    f.write_rows("velocity", p.v.data(), m, 3);
    f.write_rows("angular_velocity", p.omega.data(), m, 3);
    f.write_rows("orientation", p.q.data(), m, 4);
    f.write_rows("radius", p.radius.data(), m, 1);
    f.write_rows("id", p.id.data(), m, 1);
    std::vector<double> shape(p.shape.begin(), p.shape.begin() + static_cast<std::ptrdiff_t>(m));
    f.write_rows("shape", shape.data(), m, 1);
    if (loads_) {
      f.write_rows("external_force", p.f_ext.data(), m, 3);
      f.write_rows("external_torque", p.t_ext.data(), m, 3);
    }
    f.set_attribute("time", dem.time());
    if (dem.shaped()) {
      // Template surface nodes at x + R(q) X (velocity v + w x R(q) X); triangles indexed globally:
      // this rank's nodes start after those of the ranks before it.
      std::vector<double> nodes, vel;
      std::vector<std::int64_t> tris, ids;
      for (std::size_t i = 0; i < m; ++i) {
        if (p.shape[i] == 0) continue;
        const ShapeTemplate& t = dem.shapes()[p.shape[i] - 1];
        const Quaternion q{p.q[4 * i], p.q[4 * i + 1], p.q[4 * i + 2], p.q[4 * i + 3]};
        const auto base = static_cast<std::int64_t>(nodes.size() / 3);
        for (const auto& X : t.nodes) {
          const Vec3 arm = q.rotate(X), x = p.pos(i) + arm, v = p.vel(i) + cross(p.ang(i), arm);
          nodes.insert(nodes.end(), {x.x, x.y, x.z});
          vel.insert(vel.end(), {v.x, v.y, v.z});
        }
        for (const auto& tri : t.surface) {
          tris.insert(tris.end(), {base + tri[0], base + tri[1], base + tri[2]});
          ids.push_back(p.id[i]);
        }
      }
      long mine = static_cast<long>(nodes.size() / 3), offset = 0;
      MPI_Exscan(&mine, &offset, 1, MPI_LONG, MPI_SUM, comm);
      if (comm_rank(comm) == 0) offset = 0;
      for (auto& k : tris) k += offset;
      surface_nodes = f.write_rows("surface_nodes", nodes.data(), nodes.size() / 3, 3);
      f.write_rows("surface_velocity", vel.data(), vel.size() / 3, 3);
      surface_triangles = f.write_rows("surface_triangles", tris.data(), tris.size() / 3, 3);
      f.write_rows("surface_id", ids.data(), ids.size(), 1);
    }
  }
  entries_.push_back({dem.time(), name, n, surface_nodes, surface_triangles, loads_});
  if (comm_rank(comm) == 0) {
    std::string bodies, grains;
    for (std::size_t k = 0; k < entries_.size(); ++k) {
      bodies += grid_xml(k, "", false);
      if (dem.shaped()) grains += grid_xml(k, "", true);
    }
    write_file_atomically(dir_ + "/particles.xmf", temporal_index("bodies", bodies));
    if (dem.shaped()) write_file_atomically(dir_ + "/grains.xmf", temporal_index("grains", grains));
  }
}

std::string SnapshotSeries::grid_xml(std::size_t k, const std::string& prefix, bool surfaces) const {
  const Entry& e = entries_.at(k);
  return surfaces ? grains_grid(e.time, prefix + e.file, e.surface_nodes, e.surface_triangles)
                  : bodies_grid(e.time, prefix + e.file, e.bodies, e.loads);
}

void write_checkpoint(const std::string& path, DemSolver& dem, const CheckpointExtras& extras) {
  dem.complete_step();
  MPI_Comm comm = dem.decomposition().comm();
  const ParticleStore& p = dem.particles();
  const std::string tmp = path + ".tmp";
  {
    H5File f = H5File::create(tmp, comm);
    std::vector<double> state;
    state.reserve(static_cast<std::size_t>(p.packed_size()) * p.owned);
    for (std::size_t i = 0; i < p.owned; ++i) p.pack(i, state);
    f.write_rows("bodies", state.data(), p.owned, p.packed_size());
    // Each pair's history is kept by every rank evaluating it; the owner of the lower key writes it
    // (owned bodies are stored sorted by key).
    std::vector<std::uint64_t> keys;
    std::vector<double> hist;
    const auto owned_end = p.order.begin() + static_cast<std::ptrdiff_t>(p.owned);
    for (const auto& [key, h] : dem.histories()) {
      const auto lo = key_low(key) / dem.key_stride();  // the lower element's body
      const auto it = std::lower_bound(p.order.begin(), owned_end, lo);
      if (it == owned_end || *it != lo) continue;
      keys.push_back(key);
      hist.insert(hist.end(), h.begin(), h.end());
    }
    f.write_rows("pair_keys", keys.data(), keys.size(), 1);
    f.write_rows("pair_history", hist.data(), keys.size(), 3);
    // Mesh walls' motion state (the same on every rank; rank 0 writes it).
    std::vector<double> mesh;
    if (comm_rank(comm) == 0)
      for (const auto& m : dem.walls().meshes()) {
        const double row[kMeshStateSize] = {m.origin.x, m.origin.y,   m.origin.z,   m.q.w,        m.q.x,     m.q.y,
                                            m.q.z,      m.velocity.x, m.velocity.y, m.velocity.z, m.omega.x, m.omega.y,
                                            m.omega.z,  m.theta,      m.theta_dot,  m.theta_ddot};
        mesh.insert(mesh.end(), row, row + kMeshStateSize);
      }
    f.write_rows("mesh_state", mesh.data(), mesh.size() / kMeshStateSize, kMeshStateSize);
    // Free spheres (T17): state and wall springs, the same on every rank (rank 0 writes them).
    std::vector<double> spheres, sphere_hist;
    std::vector<std::uint64_t> sphere_keys;
    if (comm_rank(comm) == 0) {
      for (const auto& b : dem.free_spheres())
        for (const Vec3& v : {b.x, b.v, b.omega, b.force, b.torque}) spheres.insert(spheres.end(), {v.x, v.y, v.z});
      for (const auto& [key, h] : dem.free_sphere_histories()) {
        sphere_keys.push_back(key);
        sphere_hist.insert(sphere_hist.end(), h.begin(), h.end());
      }
    }
    if (!dem.free_spheres().empty()) {
      f.write_rows("free_sphere_state", spheres.data(), spheres.size() / kFreeSphereStateSize, kFreeSphereStateSize);
      f.write_rows("free_sphere_history_keys", sphere_keys.data(), sphere_keys.size(), 1);
      f.write_rows("free_sphere_history", sphere_hist.data(), sphere_keys.size(), 3);
    }
    f.set_attribute("format", std::string("tessera-dem-checkpoint-3"));
    f.set_attribute("time", dem.time());
    f.set_attribute("steps", dem.steps());
    f.set_attribute("wall_slots", static_cast<long>(p.wall_slots));
    for (const auto& [k, v] : extras) f.set_attribute("extra:" + k, v);
    std::string names;
    for (const auto& [k, v] : extras) names += k + "\n";
    f.set_attribute("extras", names);
  }
  MPI_Barrier(comm);
  if (comm_rank(comm) == 0) fs::rename(tmp, path);
  MPI_Barrier(comm);
}

CheckpointExtras read_checkpoint(const std::string& path, DemSolver& dem) {
  MPI_Comm comm = dem.decomposition().comm();
  H5File f = H5File::open_read(path, comm);
  const std::string format = f.attribute_string("format");
  if (format != "tessera-dem-checkpoint-3" && format != "tessera-dem-checkpoint-2")
    throw InputError("restart", path, "a Tessera DEM checkpoint (format tessera-dem-checkpoint-3 or -2)");
  auto& meshes = dem.walls().meshes();
  if (f.has("mesh_state") || !meshes.empty()) {
    int mcols = 0;
    const auto mesh = f.has("mesh_state") ? f.read_all<double>("mesh_state", mcols) : std::vector<double>{};
    if (mesh.size() != meshes.size() * kMeshStateSize)
      throw InputError(
          "restart", path,
          "a checkpoint made with the same mesh walls as this case (" + std::to_string(meshes.size()) + ")");
    for (std::size_t k = 0; k < meshes.size(); ++k) {
      const double* r = &mesh[k * kMeshStateSize];
      MeshWall& m = meshes[k];
      m.origin = {r[0], r[1], r[2]};
      m.q = {r[3], r[4], r[5], r[6]};
      m.velocity = {r[7], r[8], r[9]};
      m.omega = {r[10], r[11], r[12]};
      m.theta = r[13], m.theta_dot = r[14], m.theta_ddot = r[15];
      m.place();
    }
  }
  // Free spheres: a checkpoint without them (a bed) leaves the case's initial state, one with
  // them must hold as many as the case declares.
  auto& spheres = dem.free_spheres();
  if (f.has("free_sphere_state")) {
    int scols = 0;
    const auto state = f.read_all<double>("free_sphere_state", scols);
    if (state.size() != spheres.size() * kFreeSphereStateSize)
      throw InputError(
          "restart", path,
          "a checkpoint made with the same free spheres as this case (" + std::to_string(spheres.size()) + ")");
    for (std::size_t k = 0; k < spheres.size(); ++k) {
      const double* r = &state[k * kFreeSphereStateSize];
      FreeSphere& b = spheres[k];
      b.x = {r[0], r[1], r[2]}, b.v = {r[3], r[4], r[5]}, b.omega = {r[6], r[7], r[8]};
      b.force = {r[9], r[10], r[11]}, b.torque = {r[12], r[13], r[14]};
      b.x_build = b.x;
    }
    int kc = 0, hc = 0;
    const auto keys = f.read_all<std::uint64_t>("free_sphere_history_keys", kc);
    const auto hist = f.read_all<double>("free_sphere_history", hc);
    HistoryMap h;
    for (std::size_t k = 0; k < keys.size(); ++k) h[keys[k]] = {hist[3 * k], hist[3 * k + 1], hist[3 * k + 2]};
    dem.set_free_sphere_histories(std::move(h));
  }
  ParticleStore& p = dem.particles();
  if (f.attribute_long("wall_slots") != p.wall_slots)
    throw InputError(
        "restart", path,
        "a checkpoint made with the same walls as this case (" + std::to_string(p.wall_slots) + " wall primitives)");
  int cols = 0;
  const auto state = f.read_all<double>("bodies", cols);
  // Checkpoints written before bodies carried external loads lack their 6 columns (loads zero).
  const bool with_loads = cols == p.packed_size();
  if (!with_loads && cols != p.packed_size_without_loads())
    throw InputError("restart", path, "a checkpoint with the same body layout");
  const Decomposition& decomp = dem.decomposition();
  for (std::size_t off = 0; off < state.size(); off += static_cast<std::size_t>(cols)) {
    const Vec3 x{state[off + 6], state[off + 7], state[off + 8]};
    if (decomp.owns(x)) p.unpack_append(&state[off], with_loads);
  }
  p.owned = p.size();
  const auto keys = f.read_all<std::uint64_t>("pair_keys", cols);
  const auto hist = f.read_all<double>("pair_history", cols);
  HistoryMap h;
  for (std::size_t k = 0; k < keys.size(); ++k) h[keys[k]] = {hist[3 * k], hist[3 * k + 1], hist[3 * k + 2]};
  dem.preload_histories(std::move(h));
  dem.set_clock(f.attribute_double("time"), f.attribute_long("steps"));
  CheckpointExtras extras;
  std::istringstream names(f.attribute_string("extras"));
  for (std::string k; std::getline(names, k);)
    if (!k.empty()) extras[k] = f.attribute_double("extra:" + k);
  return extras;
}

std::map<std::int64_t, Vec3> read_checkpoint_positions(const std::string& path) {
  H5File f = H5File::open_read(path, MPI_COMM_SELF);
  int cols = 0;
  const auto state = f.read_all<double>("bodies", cols);
  std::map<std::int64_t, Vec3> x;
  for (std::size_t off = 0; off + 8 < state.size(); off += static_cast<std::size_t>(cols))
    x[static_cast<std::int64_t>(state[off])] = {state[off + 6], state[off + 7], state[off + 8]};  // ParticleStore::pack
  return x;
}

void write_lammps_data(const std::string& path, const DemSolver& dem) {
  MPI_Comm comm = dem.decomposition().comm();
  const ParticleStore& p = dem.particles();
  constexpr int cols = 12;  // id type diameter density x y z vx vy vz molecule 0 (wx wy wz below)
  std::vector<double> rows;
  for (std::size_t i = 0; i < p.owned; ++i) {
    const int sh = p.shape[i];
    if (sh == 0) {
      const double vol = 4.0 / 3.0 * std::numbers::pi * std::pow(p.radius[i], 3);
      const double r[cols] = {static_cast<double>(p.id[i]),
                              static_cast<double>(p.material[i] + 1),
                              2 * p.radius[i],
                              p.mass[i] / vol,
                              p.x[3 * i],
                              p.x[3 * i + 1],
                              p.x[3 * i + 2],
                              p.v[3 * i],
                              p.v[3 * i + 1],
                              p.v[3 * i + 2],
                              static_cast<double>(p.id[i]),
                              0};
      rows.insert(rows.end(), r, r + cols);
      rows.insert(rows.end(), &p.omega[3 * i], &p.omega[3 * i] + 3);
      continue;
    }
    // A shaped body: its contact spheres, molecule id = body id, the body's mass split evenly.
    const ShapeTemplate& t = dem.shapes()[sh - 1];
    const Quaternion q{p.q[4 * i], p.q[4 * i + 1], p.q[4 * i + 2], p.q[4 * i + 3]};
    const double count = static_cast<double>(t.spheres.size());
    const double rho = p.mass[i] / count / (4.0 / 3.0 * std::numbers::pi * std::pow(t.sphere_radius, 3));
    const Vec3 w = p.ang(i);
    for (std::size_t k = 0; k < t.spheres.size(); ++k) {
      const Vec3 arm = q.rotate(t.spheres[k]), x = p.pos(i) + arm, v = p.vel(i) + cross(w, arm);
      const double r[cols] = {static_cast<double>((p.id[i] - 1) * dem.key_stride() + static_cast<long>(k) + 1),
                              static_cast<double>(p.material[i] + 1),
                              2 * t.sphere_radius,
                              rho,
                              x.x,
                              x.y,
                              x.z,
                              v.x,
                              v.y,
                              v.z,
                              static_cast<double>(p.id[i]),
                              0};
      rows.insert(rows.end(), r, r + cols);
      rows.insert(rows.end(), &p.omega[3 * i], &p.omega[3 * i] + 3);
    }
  }
  constexpr int stride = cols + 3;
  int size = 1, mine = static_cast<int>(rows.size());
  MPI_Comm_size(comm, &size);
  std::vector<int> counts(size), displs(size, 0);
  MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  const bool root = comm_rank(comm) == 0;
  std::vector<double> all;
  if (root) {
    for (int r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
    all.resize(static_cast<std::size_t>(displs[size - 1] + counts[size - 1]));
  }
  MPI_Gatherv(rows.data(), mine, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0, comm);
  if (!root) return;
  const std::size_t n = all.size() / stride;
  std::vector<std::size_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return all[a * stride] < all[b * stride]; });
  const Vec3 lo = dem.decomposition().global_lo(), hi = dem.decomposition().global_hi();
  std::ostringstream o;
  o << std::setprecision(17);
  o << "LAMMPS data file written by Tessera (atom_style sphere), t = " << dem.time() << " s\n\n"
    << n << " atoms\n"
    << dem.model().material_count() << " atom types\n\n"
    << lo.x << " " << hi.x << " xlo xhi\n"
    << lo.y << " " << hi.y << " ylo yhi\n"
    << lo.z << " " << hi.z << " zlo zhi\n\nAtoms # sphere\n\n";
  for (const auto k : order) {
    const double* r = &all[k * stride];
    o << static_cast<long>(r[0]) << " " << static_cast<int>(r[1]) << " " << r[2] << " " << r[3] << " " << r[4] << " "
      << r[5] << " " << r[6] << "\n";
  }
  o << "\nVelocities\n\n";
  for (const auto k : order) {
    const double* r = &all[k * stride];
    o << static_cast<long>(r[0]) << " " << r[7] << " " << r[8] << " " << r[9] << " " << r[12] << " " << r[13] << " "
      << r[14] << "\n";
  }
  if (dem.shaped()) {
    // For `fix property/atom mol` (read_data ... fix ID NULL Molecules): LAMMPS fix rigid/small.
    o << "\nMolecules\n\n";
    for (const auto k : order) {
      const double* r = &all[k * stride];
      o << static_cast<long>(r[0]) << " " << static_cast<long>(r[10]) << "\n";
    }
  }
  write_file_atomically(path, o.str());
}

long read_lammps_data(const std::string& path, DemSolver& dem, const std::vector<int>& type_materials,
                      const std::string& key) {
  std::ifstream in(path);
  if (!in) throw InputError(key, path, "a readable LAMMPS data file");
  std::string line;
  long declared = -1;
  struct Row {
    long id;
    int type;
    double d, rho;
    Vec3 x, v, w;
  };
  std::map<long, Row> rows;
  enum { header, atoms, velocities, other } section = header;
  std::getline(in, line);  // title line
  long line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    std::string body = line.substr(0, hash);
    std::istringstream s(body);
    std::string first;
    if (!(s >> first)) continue;
    if (first == "Atoms") {
      if (line.find("sphere") == std::string::npos && hash != std::string::npos)
        throw InputError(key, path, "atom_style sphere data (Atoms # sphere)");
      section = atoms;
      continue;
    }
    if (first == "Velocities") {
      section = velocities;
      continue;
    }
    if (std::isalpha(static_cast<unsigned char>(first[0]))) {
      section = other;
      continue;
    }
    if (section == header) {
      if (body.find("atoms") != std::string::npos) declared = std::stol(first);
      continue;
    }
    std::istringstream r(body);
    if (section == atoms) {
      Row row{};
      if (!(r >> row.id >> row.type >> row.d >> row.rho >> row.x.x >> row.x.y >> row.x.z))
        throw InputError(key, path + ":" + std::to_string(line_no), "lines 'id type diameter density x y z'");
      if (row.type < 1 || row.type > static_cast<int>(type_materials.size()))
        throw InputError(key, path + ":" + std::to_string(line_no),
                         "atom types 1.." + std::to_string(type_materials.size()) + " (one material per type)");
      if (!(row.d > 0) || !(row.rho > 0))
        throw InputError(key, path + ":" + std::to_string(line_no), "positive diameter and density");
      rows[row.id] = row;
    } else if (section == velocities) {
      long id = 0;
      Vec3 v, w;
      if (!(r >> id >> v.x >> v.y >> v.z >> w.x >> w.y >> w.z))
        throw InputError(key, path + ":" + std::to_string(line_no), "velocity lines 'id vx vy vz wx wy wz'");
      const auto it = rows.find(id);
      if (it == rows.end()) throw InputError(key, path + ":" + std::to_string(line_no), "velocities of known atoms");
      it->second.v = v, it->second.w = w;
    }
  }
  if (declared >= 0 && declared != static_cast<long>(rows.size()))
    throw InputError(key, path,
                     std::to_string(declared) + " atoms as its header declares, found " + std::to_string(rows.size()));
  const Vec3 lo = dem.decomposition().global_lo(), hi = dem.decomposition().global_hi();
  for (const auto& [id, row] : rows) {
    for (int d = 0; d < 3; ++d)
      if (row.x[d] < lo[d] || row.x[d] > hi[d])
        throw InputError(key, path, "bodies inside domain.box (body " + std::to_string(id) + " is outside)");
    dem.add_sphere(id, type_materials[row.type - 1], 0.5 * row.d, row.x, row.v, row.w, row.rho);
  }
  return static_cast<long>(rows.size());
}

}  // namespace tessera
