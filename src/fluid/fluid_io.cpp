// SPDX-License-Identifier: MIT
#include "fluid/fluid_io.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "core/errors.hpp"
#include "core/h5_file.hpp"
#include "core/text_file.hpp"

namespace tessera {
namespace fs = std::filesystem;
namespace {

constexpr const char* kFormat = "tessera-flow-checkpoint-1";

// This rank's block of a (z, y, x) array: offsets and counts in that order. `extra_high[d]` adds
// the domain's high face along d on the rank that holds it (face arrays).
struct Block {
  std::size_t global[3], offset[3], count[3];
  std::array<int, 3> lo, hi;  // global index box (x, y, z), hi exclusive
};

Block block_of(const FluidGrid& g, int face_dir = -1) {
  Block b;
  for (int d = 0; d < 3; ++d) {
    const bool extra = d == face_dir && !g.periodic(d) && g.end(d) == g.cells()[d];
    const int n = g.cells()[d] + (d == face_dir && !g.periodic(d) ? 1 : 0);
    b.lo[d] = g.begin(d);
    b.hi[d] = g.end(d) + (extra ? 1 : 0);
    b.global[2 - d] = std::size_t(n);
    b.offset[2 - d] = std::size_t(b.lo[d]);
    b.count[2 - d] = std::size_t(b.hi[d] - b.lo[d]);
  }
  return b;
}

std::vector<double> pack(const FluidGrid& g, const Block& b, std::initializer_list<const std::vector<double>*> comps) {
  std::vector<double> out;
  out.reserve(b.count[0] * b.count[1] * b.count[2] * comps.size());
  for (int k = b.lo[2]; k < b.hi[2]; ++k)
    for (int j = b.lo[1]; j < b.hi[1]; ++j)
      for (int i = b.lo[0]; i < b.hi[0]; ++i)
        for (const auto* c : comps) out.push_back((*c)[g.at(i, j, k)]);
  return out;
}

void unpack(const FluidGrid& g, const Block& b, const std::vector<double>& in,
            std::initializer_list<std::vector<double>*> comps) {
  std::size_t n = 0;
  for (int k = b.lo[2]; k < b.hi[2]; ++k)
    for (int j = b.lo[1]; j < b.hi[1]; ++j)
      for (int i = b.lo[0]; i < b.hi[0]; ++i)
        for (auto* c : comps) (*c)[g.at(i, j, k)] = in[n++];
}

int comm_rank(MPI_Comm comm) {
  int r = 0;
  MPI_Comm_rank(comm, &r);
  return r;
}

}  // namespace

void FieldSeries::write(const FlowSolver& flow) {
  const FluidGrid& g = flow.grid();
  const bool root = comm_rank(g.comm()) == 0;
  if (root) fs::create_directories(dir_);
  MPI_Barrier(g.comm());
  char name[64];
  std::snprintf(name, sizeof name, "fields_%05d.h5", count());
  {
    H5File f = H5File::create(dir_ + "/" + name, g.comm());
    f.set_attribute("time", flow.time());
    f.set_attribute("steps", flow.steps());
    const Block b = block_of(g);
    f.write_block("liquid_fraction", pack(g, b, {&flow.fraction()}).data(), b.global, b.offset, b.count, 1);
    f.write_block("velocity", pack(g, b, {&flow.velocity(0), &flow.velocity(1), &flow.velocity(2)}).data(), b.global,
                  b.offset, b.count, 3);
    f.write_block("pressure", pack(g, b, {&flow.pressure()}).data(), b.global, b.offset, b.count, 1);
    for (const auto& [nm, field] : extra_) f.write_block(nm, pack(g, b, {field}).data(), b.global, b.offset, b.count, 1);
  }
  times_.push_back(flow.time());
  if (!root) return;
  std::string grids;
  for (int k = 0; k < count(); ++k) grids += grid_xml(g, k, "");
  write_file_atomically(dir_ + "/fields.xmf", "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n"
                                               "<Grid Name=\"flow\" GridType=\"Collection\" CollectionType=\"Temporal\">\n" +
                                                   grids + "</Grid>\n</Domain>\n</Xdmf>\n");
}

// A 3DCoRectMesh (dimensions, origin and spacing in z, y, x order) with cell data.
std::string FieldSeries::grid_xml(const FluidGrid& g, int s, const std::string& prefix) const {
  const auto& n = g.cells();
  std::ostringstream x;
  x.precision(17);
  const std::string dims = std::to_string(n[2]) + " " + std::to_string(n[1]) + " " + std::to_string(n[0]);
  char name[64];
  std::snprintf(name, sizeof name, "fields_%05d.h5", s);
  const std::string file = prefix + name;
  x << "<Grid Name=\"fields\" GridType=\"Uniform\">\n<Time Value=\"" << times_.at(std::size_t(s)) << "\"/>\n"
    << "<Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << n[2] + 1 << " " << n[1] + 1 << " " << n[0] + 1
    << "\"/>\n<Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
    << "<DataItem Dimensions=\"3\" Format=\"XML\">" << g.lo().z << " " << g.lo().y << " " << g.lo().x
    << "</DataItem>\n<DataItem Dimensions=\"3\" Format=\"XML\">" << g.h(2) << " " << g.h(1) << " " << g.h(0)
    << "</DataItem>\n</Geometry>\n";
  auto attr = [&](const std::string& nm, const char* type, int comps) {
    x << "<Attribute Name=\"" << nm << "\" AttributeType=\"" << type << "\" Center=\"Cell\">\n"
      << "<DataItem Dimensions=\"" << dims << (comps > 1 ? " 3" : "")
      << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << file << ":/" << nm << "</DataItem>\n"
      << "</Attribute>\n";
  };
  attr("liquid_fraction", "Scalar", 1);
  attr("velocity", "Vector", 3);
  attr("pressure", "Scalar", 1);
  for (const auto& e : extra_) attr(e.first, "Scalar", 1);
  x << "</Grid>\n";
  return x.str();
}


void write_flow_checkpoint(const std::string& path, const FlowSolver& flow, const std::vector<NamedCellField>& extra,
                           const Decomposition::Cuts* cuts) {
  const FluidGrid& g = flow.grid();
  const std::string tmp = path + ".tmp";
  {
    H5File f = H5File::create(tmp, g.comm());
    f.set_attribute("format", std::string(kFormat));
    f.set_attribute("time", flow.time());
    f.set_attribute("steps", flow.steps());
    f.set_attribute("last_dt", flow.last_dt());
    if (cuts)
      for (int d = 0; d < 3; ++d) {
        std::ostringstream v;
        v.precision(17);
        for (double c : (*cuts)[d]) v << c << ' ';
        f.set_attribute(std::string("interior_cuts_") + "xyz"[d], (*cuts)[d].empty() ? std::string("-") : v.str());
      }
    const Block b = block_of(g);
    f.write_block("liquid_fraction", pack(g, b, {&flow.fraction()}).data(), b.global, b.offset, b.count, 1);
    f.write_block("velocity", pack(g, b, {&flow.velocity(0), &flow.velocity(1), &flow.velocity(2)}).data(), b.global,
                  b.offset, b.count, 3);
    f.write_block("pressure", pack(g, b, {&flow.pressure()}).data(), b.global, b.offset, b.count, 1);
    for (int d = 0; d < 3; ++d) {
      const Block fb = block_of(g, d);
      const std::string nm = std::string("face_velocity_") + "xyz"[d];
      f.write_block(nm, pack(g, fb, {&flow.face_velocity(d)}).data(), fb.global, fb.offset, fb.count, 1);
    }
    for (const auto& [name, field] : extra)
      f.write_block(name, pack(g, b, {field}).data(), b.global, b.offset, b.count, 1);
    if (flow.settings().energy_budget) {  // F12a: the budget goes on after a restart or a rebalance
      const FlowSolver::EnergyBudget& e = flow.energy_budget();
      f.set_attribute("energy_advection", e.advection);
      f.set_attribute("energy_viscous", e.viscous);
      f.set_attribute("energy_projection", e.projection);
      f.write_block("advection_energy_source", pack(g, b, {&flow.advection_energy_source()}).data(), b.global,
                    b.offset, b.count, 1);
    }
  }
  MPI_Barrier(g.comm());
  if (comm_rank(g.comm()) == 0) fs::rename(tmp, path);
  MPI_Barrier(g.comm());
}

void read_flow_checkpoint(const std::string& path, FlowSolver& flow) {
  const FluidGrid& g = flow.grid();
  H5File f = H5File::open_read(path, g.comm());
  if (!f.has("liquid_fraction") || f.attribute_string("format") != kFormat)
    throw InputError("--restart", path, std::string("a flow checkpoint (") + kFormat + ")");
  const Block b = block_of(g);
  unpack(g, b, f.read_block("liquid_fraction", b.global, b.offset, b.count, 1), {&flow.mutable_fraction()});
  unpack(g, b, f.read_block("velocity", b.global, b.offset, b.count, 3),
         {&flow.mutable_velocity(0), &flow.mutable_velocity(1), &flow.mutable_velocity(2)});
  unpack(g, b, f.read_block("pressure", b.global, b.offset, b.count, 1), {&flow.mutable_pressure()});
  for (int d = 0; d < 3; ++d) {
    const Block fb = block_of(g, d);
    const std::string nm = std::string("face_velocity_") + "xyz"[d];
    unpack(g, fb, f.read_block(nm, fb.global, fb.offset, fb.count, 1), {&flow.mutable_face_velocity(d)});
  }
  flow.set_clock(f.attribute_double("time"), f.attribute_long("steps"), f.attribute_double("last_dt"));
  // F12a: a checkpoint written with the energy budget carries it on; one without starts it at zero.
  if (flow.settings().energy_budget && f.has_attribute("energy_advection") && f.has("advection_energy_source")) {
    flow.set_energy_budget({f.attribute_double("energy_advection"), f.attribute_double("energy_viscous"),
                            f.attribute_double("energy_projection")});
    unpack(g, b, f.read_block("advection_energy_source", b.global, b.offset, b.count, 1),
           {&flow.mutable_advection_energy_source()});
  }
  flow.refresh();
}

std::optional<Decomposition::Cuts> read_checkpoint_cuts(const std::string& path, MPI_Comm comm) {
  H5File f = H5File::open_read(path, comm);
  if (!f.has_attribute("interior_cuts_x")) return std::nullopt;
  Decomposition::Cuts cuts;
  for (int d = 0; d < 3; ++d) {
    std::istringstream v(f.attribute_string(std::string("interior_cuts_") + "xyz"[d]));
    for (double c; v >> c;) cuts[d].push_back(c);
  }
  return cuts;
}

void read_checkpoint_cell_field(const std::string& path, const FluidGrid& g, const std::string& name,
                                std::vector<double>& field, const std::string& what) {
  H5File f = H5File::open_read(path, g.comm());
  if (!f.has(name)) throw InputError("--restart", path, "a checkpoint with " + name + " (" + what + ")");
  const Block b = block_of(g);
  unpack(g, b, f.read_block(name, b.global, b.offset, b.count, 1), {&field});
  g.exchange(field);
}

}  // namespace tessera
