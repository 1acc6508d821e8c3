// SPDX-License-Identifier: MIT
// Bed: runs a bed read from a LAMMPS data file (atom_style sphere) or from a Tessera checkpoint
// (a file ending in .h5: bodies, shapes, contact histories; the clock restarts at 0) for
// run.end_time or run.max_steps, or until it settles (bed.settled_kinetic_energy, bed.min_time,
// as a deposition's): the scene the DEM benchmarks time against LAMMPS and LIGGGHTS on the
// same bed.
#include <filesystem>

#include "app/dem_scene.hpp"
#include "app/scenes.hpp"
#include "core/errors.hpp"

namespace tessera {

namespace {

class BedScene final : public DemScene {
 public:
  BedScene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir) : DemScene(root, comm, case_dir) {
    const ConfigNode b = root.section("bed");
    file_ = resolve_path(b.text("file"));
    if (!std::filesystem::is_regular_file(file_))
      b.fail("file", "an existing LAMMPS data file or Tessera checkpoint (" + file_ + ")");
    checkpoint_ = std::filesystem::path(file_).extension() == ".h5";
    if (!checkpoint_) {
      for (const auto& m : b.texts("type_materials"))
        types_.push_back(dem_->model().material_index(m, b.key_path("type_materials")));
      if (types_.empty()) b.fail("type_materials", "a list naming the material of each LAMMPS atom type");
      require_pairs(types_);
    }
    if (!end_time_ && !max_steps_) root.section("run").fail("end_time", "run.end_time or run.max_steps");
    settle_ = SettleCriterion(b, false);
  }
  const char* name() const override { return "bed"; }

 protected:
  void create_bodies() override {
    if (checkpoint_) {
      read_checkpoint(file_, *dem_);
      dem_->set_clock(0.0, 0);
    } else {
      read_lammps_data(file_, *dem_, types_, "bed.file");
    }
  }
  bool continues_state() const override { return checkpoint_; }
  bool finished(const DemStats& s) override { return settle_.check(s, dem_->time()); }
  void restore(const CheckpointExtras& e) override { settle_.restore(e); }
  CheckpointExtras extras() const override {
    CheckpointExtras e;
    if (settle_.enabled()) settle_.save(e);
    return e;
  }
  void quantities(nlohmann::json& q) override {
    if (settle_.enabled()) settle_.report(q, dem_->time());
  }

 private:
  std::string file_;
  bool checkpoint_ = false;
  std::vector<int> types_;
  SettleCriterion settle_;
};

}  // namespace

std::unique_ptr<DemScene> make_bed_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir) {
  return std::make_unique<BedScene>(root, comm, dir);
}

}  // namespace tessera
