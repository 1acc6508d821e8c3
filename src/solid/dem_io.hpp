// SPDX-License-Identifier: MIT
// DEM input/output: snapshots (HDF5 + an XDMF time series ParaView opens), checkpoints (HDF5,
// written to a temporary name then renamed, so a kill mid-write loses nothing) and LAMMPS data
// files (atom_style sphere: id type diameter density x y z), so beds move between Tessera, LAMMPS
// and LIGGGHTS.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "solid/dem_solver.hpp"

namespace tessera {

class SnapshotSeries {
 public:
  explicit SnapshotSeries(std::string dir) : dir_(std::move(dir)) {}
  // On: each snapshot also holds the bodies' external loads (ParticleStore::f_ext, t_ext: the
  // fluid's force and moment in a coupled run) as external_force and external_torque.
  void write_loads(bool on) { loads_ = on; }
  // Collective: writes DIR/particles_NNNNNN.h5 and rewrites DIR/particles.xmf; with shaped bodies
  // also DIR/grains.xmf: each body's template surface (triangles) placed at its position and
  // orientation, so that ParaView draws every grain's shape. Completes the step first (DemSolver::complete_step).
  void write(DemSolver& dem);
  std::size_t count() const { return entries_.size(); }
  double time_of(std::size_t k) const { return entries_.at(k).time; }
  // The XDMF <Grid> of snapshot k: the bodies (Polyvertex) or, surfaces = true, the grains'
  // surfaces; `prefix` goes before the HDF5 file's name (an index in another directory).
  std::string grid_xml(std::size_t k, const std::string& prefix, bool surfaces) const;

 private:
  struct Entry {
    double time;
    std::string file;
    long bodies;
    long surface_nodes = 0, surface_triangles = 0;
    bool loads = false;
  };
  std::string dir_;
  bool loads_ = false;
  std::vector<Entry> entries_;
};

// Extra scalar state a scene keeps in its checkpoint (e.g. its stage), by name.
using CheckpointExtras = std::map<std::string, double>;

// Collective. Completes the step first (DemSolver::complete_step).
void write_checkpoint(const std::string& path, DemSolver& dem, const CheckpointExtras& extras = {});
// Collective: loads bodies owned by this rank, the histories and the clock; returns the extras.
// Call before dem.setup(false).
CheckpointExtras read_checkpoint(const std::string& path, DemSolver& dem);

// Every body's position in a checkpoint, by id (each caller reads the file; not collective).
std::map<std::int64_t, Vec3> read_checkpoint_positions(const std::string& path);

// Collective: gathers on rank 0, writes bodies sorted by id. Types are material index + 1.
// Shaped bodies are written as their contact spheres (molecule id = body id, mass split evenly) with
// a Molecules section, for LAMMPS fix property/atom mol + fix rigid/small.
void write_lammps_data(const std::string& path, const DemSolver& dem);
// Collective: every rank reads the file and keeps its own bodies. type_materials[t - 1] is the
// material of LAMMPS type t; the mass comes from the file's per-atom density, as in LAMMPS.
// Returns the number of bodies read.
long read_lammps_data(const std::string& path, DemSolver& dem, const std::vector<int>& type_materials,
                      const std::string& key_for_errors);

}  // namespace tessera
