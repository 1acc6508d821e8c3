// SPDX-License-Identifier: MIT
// Flow fields on disk (parallel HDF5, one collective write per dataset):
//  - snapshots: DIR/fields_NNNNN.h5 with liquid_fraction, velocity (3 components), pressure as
//    (z, y, x) cell arrays, and DIR/fields.xmf, a temporal collection on a 3DCoRectMesh that
//    ParaView opens (cell data);
//  - checkpoints: every field the next step needs (f, u, p, face velocities including the
//    domain's high faces, clock and last dt), restarting bit for bit at the same rank count.
#pragma once
#include <string>
#include <vector>

#include "fluid/flow_solver.hpp"

namespace tessera {

class FieldSeries {
 public:
  explicit FieldSeries(std::string dir) : dir_(std::move(dir)) {}
  // Collective. Writes one snapshot and rewrites the XDMF index (rank 0).
  void write(const FlowSolver& flow);
  int count() const { return int(times_.size()); }
  bool written_at(double time) const { return !times_.empty() && times_.back() == time; }

 private:
  std::string dir_;
  std::vector<double> times_;
};

// Collective.
void write_flow_checkpoint(const std::string& path, const FlowSolver& flow);
// Collective. Same grid required (checked); any rank count.
void read_flow_checkpoint(const std::string& path, FlowSolver& flow);

}  // namespace tessera
