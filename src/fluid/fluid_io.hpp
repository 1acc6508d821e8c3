// SPDX-License-Identifier: MIT
// Flow fields on disk (parallel HDF5, one collective write per dataset):
//  - snapshots: DIR/fields_NNNNN.h5 with liquid_fraction, velocity (3 components), pressure as
//    (z, y, x) cell arrays, and DIR/fields.xmf, a temporal collection on a 3DCoRectMesh that
//    ParaView opens (cell data);
//  - checkpoints: every field the next step needs (f, u, p, face velocities including the
//    domain's high faces, clock and last dt), restarting bit for bit at the same rank count.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "fluid/flow_solver.hpp"

namespace tessera {

class FieldSeries {
 public:
  explicit FieldSeries(std::string dir) : dir_(std::move(dir)) {}
  // A further cell scalar written with every snapshot (ghosted layout of the flow's grid; the
  // coupling's solid fraction). The pointer must outlive the series. A name added again takes the
  // new pointer (the coupling made anew after a repartition).
  void add_field(std::string name, const std::vector<double>* field) {
    for (auto& e : extra_)
      if (e.first == name) {
        e.second = field;
        return;
      }
    extra_.emplace_back(std::move(name), field);
  }
  // Collective. Writes one snapshot and rewrites the XDMF index (rank 0).
  void write(const FlowSolver& flow);
  int count() const { return int(times_.size()); }
  bool written_at(double time) const { return !times_.empty() && times_.back() == time; }
  double time_of(int s) const { return times_.at(std::size_t(s)); }
  // The XDMF <Grid> of snapshot s; `prefix` goes before the HDF5 file's name.
  std::string grid_xml(const FluidGrid& g, int s, const std::string& prefix) const;

 private:
  std::string dir_;
  std::vector<double> times_;
  std::vector<std::pair<std::string, const std::vector<double>*>> extra_;
};

// Collective. `extra`: further cell scalars (ghosted layout of the flow's grid) saved beside the
// flow's own (the coupling's liquid content).
using NamedCellField = std::pair<std::string, const std::vector<double>*>;
// `cuts`: the decomposition's interior cut planes, kept as attributes (a balanced run's restart
// takes them back: read_checkpoint_cuts).
void write_flow_checkpoint(const std::string& path, const FlowSolver& flow, const std::vector<NamedCellField>& extra = {},
                           const Decomposition::Cuts* cuts = nullptr);
// Collective: the interior cut planes a checkpoint was written with, if it kept them.
std::optional<Decomposition::Cuts> read_checkpoint_cuts(const std::string& path, MPI_Comm comm);
// Collective. Same grid required (checked); any rank count.
void read_flow_checkpoint(const std::string& path, FlowSolver& flow);
// Collective: one of the extra cell scalars of a flow checkpoint into `field` (owned cells; ghosts
// exchanged). A checkpoint without it is an InputError naming `what`.
void read_checkpoint_cell_field(const std::string& path, const FluidGrid& grid, const std::string& name,
                                std::vector<double>& field, const std::string& what);

}  // namespace tessera
