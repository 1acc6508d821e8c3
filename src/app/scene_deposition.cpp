// SPDX-License-Identifier: MIT
// Deposition: grains start on a loose jittered lattice in a region of the box and settle under
// gravity until the total kinetic energy falls below `deposition.settled_kinetic_energy`. The
// settled bed is the run's checkpoint (DIR/checkpoint.h5, a start for later scenes) and a LAMMPS
// data file (DIR/bed.data) for peers. Reports packing fraction and coordination number.
// Grains are spheres of `diameter`, or bodies of the shape template `shape` (solid.shapes), each
// turned to a random orientation (uniform over rotations, from the seed and the grain id).
//
// The drop-impact seed's boosted fall (section 3.(3)a): with `fall_gravity_factor` F > 1 the grains
// fall under F times gravity until the highest grain meets the bed (its downward speed falls below
// half the free-fall speed F g t it would have), then gravity returns to its value and the bed runs
// `after_landing` longer; that ends the run (no energy criterion).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "app/dem_scene.hpp"
#include "app/scenes.hpp"
#include "core/errors.hpp"
#include "core/exact_sum.hpp"

namespace tessera {

namespace {

// Counter-based jitter: the same for a given (seed, id) on any rank count.
double unit_random(std::uint64_t seed, std::uint64_t id, int k) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ULL + id * 0xBF58476D1CE4E5B9ULL +
                    static_cast<std::uint64_t>(k + 1) * 0x94D049BB133111EBULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;  // [0, 1)
}

class DepositionScene final : public DemScene {
 public:
  DepositionScene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir) : DemScene(root, comm, case_dir) {
    const ConfigNode d = root.section("deposition");
    material_ = dem_->model().material_index(d.text("material"), d.key_path("material"));
    const std::string shape = d.text("shape", "sphere");
    if (shape != "sphere") {
      const auto& shapes = dem_->shapes();
      for (std::size_t k = 0; k < shapes.size(); ++k)
        if (shapes[k].name == shape) shape_ = static_cast<int>(k) + 1;
      if (shape_ == 0) d.fail("shape", "'sphere' or the name of a shape in solid.shapes");
      diameter_ = 2 * shapes[shape_ - 1].bounding_radius;  // the lattice must clear any orientation
    } else {
      diameter_ = d.real("diameter", Dim::length, Range::positive());
      // Sizes uniform in diameter (1 +- spread): a spread breaks the crystalline patches that equal
      // discs or spheres form; each grain's size comes from (seed, id), the same on any rank count.
      spread_ = d.real("diameter_spread", Dim::none, Range::half_open(0, 1), 0.0);
    }
    // Extent of a grain along each axis: any orientation needs the bounding diameter; aligned
    // shaped grains (body frame = world frame) need their contact spheres' extent.
    const double largest = diameter_ * (1 + spread_);
    Vec3 extent{largest, largest, largest};
    if (shape_ > 0) {
      aligned_ = d.choice("orientation", {"random", "aligned"}, "random") == "aligned";
      if (aligned_) {
        const ShapeTemplate& t = dem_->shapes()[shape_ - 1];
        extent = {};
        for (const auto& c : t.spheres)
          for (int k = 0; k < 3; ++k) extent[k] = std::max(extent[k], 2 * (std::fabs(c[k]) + t.sphere_radius));
      }
    }
    if (d.is_list("lattice_spacing")) {
      spacing_ = d.vec3("lattice_spacing", Dim::length);
    } else {
      const double s = d.real("lattice_spacing", Dim::length, Range::positive(), 1.1 * diameter_);
      spacing_ = {s, s, s};
    }
    jitter_ = d.real("jitter", Dim::length, Range::non_negative(), 0.03 * diameter_);
    for (int k = 0; k < 3; ++k) {
      if (spacing_[k] < extent[k])
        d.fail("lattice_spacing", "at least the grain's extent along each axis (" + std::to_string(extent[k]) +
                                      " m along axis " + std::to_string(k) + "), so that grains do not overlap");
      if (spacing_[k] - extent[k] < 2 * jitter_ && jitter_ > 0)
        d.fail("jitter", "at most (lattice_spacing - grain extent) / 2, so that grains start apart");
    }
    seed_ = static_cast<std::uint64_t>(d.integer("seed", 0, 1L << 40, 4711));
    region_lo_ = d.vec3("region_min", Dim::length);
    region_hi_ = d.vec3("region_max", Dim::length);
    const Vec3 lo = decomp_->global_lo(), hi = decomp_->global_hi();
    for (int k = 0; k < 3; ++k) {
      if (!(region_hi_[k] > region_lo_[k])) d.fail("region_max", "larger than region_min in every direction");
      if (region_lo_[k] < lo[k] || region_hi_[k] > hi[k])
        d.fail("region_max", "a region inside domain.box_min .. domain.box_max (grains must start in the box)");
      counts_[k] = static_cast<long>(std::floor((region_hi_[k] - region_lo_[k]) / spacing_[k]));
      if (dem_->plane_mode() && k == dem_->plane_normal()) counts_[k] = 1;  // one layer, put in the plane
      if (counts_[k] < 1) d.fail("region_max", "a region at least one lattice spacing wide");
    }
    if (counts_[0] * counts_[1] * counts_[2] > kMaxBodyId)
      d.fail("region_max", "a region holding fewer than 2^32 grains");
    // The first max_grains lattice sites (x fastest, then y, then z), if set.
    max_grains_ = d.integer("max_grains", 1, kMaxBodyId, kMaxBodyId);
    fall_factor_ = d.real("fall_gravity_factor", Dim::none, Range{1.0, 100.0, false, true}, 1.0);  // 1: no boost
    if (fall_factor_ > 1) {
      after_landing_ = d.real("after_landing", Dim::time, Range::positive());
      if (d.has("settled_kinetic_energy"))
        d.fail("settled_kinetic_energy", "absent with fall_gravity_factor: the run ends after_landing after the landing");
      gravity_ = dem_->gravity();
      if (!(norm(gravity_) > 0)) d.fail("fall_gravity_factor", "used with a non-zero solid.gravity");
    }
    settle_ = SettleCriterion(d, fall_factor_ == 1);
    if (!end_time_) root.section("run").fail("end_time", "is required: the longest the deposition may take");
    require_pairs({material_});
  }
  const char* name() const override { return "deposition"; }

 protected:
  void create_bodies() override {
    std::int64_t id = 1;
    for (long k = 0; k < counts_[2]; ++k)
      for (long j = 0; j < counts_[1]; ++j)
        for (long i = 0; i < counts_[0] && id <= max_grains_; ++i, ++id) {
          Vec3 x{region_lo_.x + (i + 0.5) * spacing_.x, region_lo_.y + (j + 0.5) * spacing_.y,
                 region_lo_.z + (k + 0.5) * spacing_.z};
          for (int c = 0; c < 3; ++c) x[c] += jitter_ * (2 * unit_random(seed_, id, c) - 1);
          if (shape_ == 0) {
            const double r = 0.5 * diameter_ * (1 + spread_ * (2 * unit_random(seed_, id, 6) - 1));
            dem_->add_sphere(id, material_, r, x, {});
            continue;
          }
          // Uniform random rotation (Shoemake 1992).
          const double u1 = unit_random(seed_, id, 3), u2 = unit_random(seed_, id, 4), u3 = unit_random(seed_, id, 5);
          const double a = std::sqrt(1 - u1), b = std::sqrt(u1), pi2 = 2 * std::numbers::pi;
          const Quaternion q = aligned_ ? Quaternion{}
                                        : Quaternion{a * std::sin(pi2 * u2), a * std::cos(pi2 * u2),
                                                     b * std::sin(pi2 * u3), b * std::cos(pi2 * u3)};
          dem_->add_body(id, material_, shape_, x, q, {});
        }
    boost_gravity();
  }

  // Before the landing, the fall's boosted gravity.
  void boost_gravity() {
    if (fall_factor_ > 1 && landing_time_ < 0) dem_->set_gravity(gravity_ * fall_factor_);
  }

  bool finished(const DemStats& s) override {
    const double t = dem_->time();
    track_mean_speed();
    if (fall_factor_ == 1) return settle_.check(s, t);
    if (landing_time_ < 0 && top_grain_landed(t)) {
      landing_time_ = t;
      dem_->set_gravity(gravity_);
    }
    return landing_time_ >= 0 && t >= landing_time_ + after_landing_ * (1 - 1e-9);
  }

  void restore(const CheckpointExtras& e) override {
    settle_.restore(e);
    if (auto it = e.find("landing_time"); it != e.end()) landing_time_ = it->second;
    if (auto it = e.find("peak_mean_speed"); it != e.end()) peak_mean_speed_ = it->second;
    boost_gravity();
  }
  CheckpointExtras extras() const override {
    CheckpointExtras e;
    settle_.save(e);
    e["landing_time"] = landing_time_;
    e["peak_mean_speed"] = peak_mean_speed_;
    return e;
  }

  void finish(const RunOptions& opt) override { write_lammps_data(opt.output_dir + "/bed.data", *dem_); }

  void quantities(nlohmann::json& q) override {
    // Packing fraction by centre counting in slabs of one diameter over the central region
    // (2 d from the side walls), averaged from 2 d above the floor to 3 d below the highest centre.
    const ParticleStore& p = dem_->particles();
    MPI_Comm comm = decomp_->comm();
    double z_top = -1e300, z_floor = 1e300;
    for (std::size_t i = 0; i < p.owned; ++i) z_top = std::max(z_top, p.x[3 * i + 2]);
    for (std::size_t i = 0; i < p.owned; ++i) z_floor = std::min(z_floor, p.x[3 * i + 2] - p.radius[i]);
    MPI_Allreduce(MPI_IN_PLACE, &z_top, 1, MPI_DOUBLE, MPI_MAX, comm);
    MPI_Allreduce(MPI_IN_PLACE, &z_floor, 1, MPI_DOUBLE, MPI_MIN, comm);
    const Vec3 lo = decomp_->global_lo(), hi = decomp_->global_hi();
    const double d = diameter_, z0 = z_floor + 2 * d, z1 = z_top - 3 * d;
    // Plane mode: an area fraction of discs (the normal's extent and margins do not count).
    const int normal = dem_->plane_normal();
    const double ax = normal == 0 ? 1.0 : (hi.x - lo.x) - 4 * d, ay = normal == 1 ? 1.0 : (hi.y - lo.y) - 4 * d;
    const double mx = normal == 0 ? -1e300 : 2 * d, my = normal == 1 ? -1e300 : 2 * d;
    ExactSum sums[2];  // solid volume, weight: exact sums, the same bits on any rank count
    for (std::size_t i = 0; i < p.owned; ++i) {
      const Vec3 x = p.pos(i);
      sums[1] += p.mass[i];
      if (x.x < lo.x + mx || x.x > hi.x - mx || x.y < lo.y + my || x.y > hi.y - my) continue;
      if (x.z < z0 || x.z >= z1) continue;
      if (normal >= 0)
        sums[0] += std::numbers::pi * p.radius[i] * p.radius[i];
      else
        sums[0] += p.shape[i] > 0 ? p.mass[i] / dem_->model().materials()[p.material[i]].density
                                  : 4.0 / 3.0 * std::numbers::pi * std::pow(p.radius[i], 3);
    }
    ExactSum::all_reduce(sums, comm);
    const double solid = sums[0].value(), weight = sums[1].value();
    const double sample = ax * ay * (z1 - z0);
    q["packing_fraction"] = (ax > 0 && ay > 0 && z1 > z0) ? solid / sample : 0.0;
    q["bed_height"] = z_top + 0.5 * d - z_floor;
    if (shape_ > 0) {
      const ShapeTemplate& t = dem_->shapes()[shape_ - 1];
      q["grain_volume"] = t.volume;
      q["grain_mass"] = t.volume * dem_->model().materials()[material_].density;
      q["grain_contact_spheres"] = t.spheres.size();
      q["grain_envelope_gap"] = t.envelope.gap;
      q["grain_envelope_overshoot"] = t.envelope.overshoot;
    }
    if (fall_factor_ > 1) {
      q["landing_time"] = landing_time_;  // -1: the top grain had not met the bed
      q["fall_gravity_factor"] = fall_factor_;
    } else {
      settle_.report(q, dem_->time());
    }
    // The seed's measure of rest: the mean speed now against its largest value at the checks.
    q["mean_speed"] = mean_speed_;
    q["peak_mean_speed"] = peak_mean_speed_;
    q["mean_speed_over_peak"] = peak_mean_speed_ > 0 ? mean_speed_ / peak_mean_speed_ : 0.0;
    // Floor reaction over the bed's weight: 1 for a hydrostatic bed, below 1 with wall friction (Janssen).
    double floor = 0;
    const auto& prims = dem_->walls().primitives();
    const std::vector<Vec3> wall_forces = dem_->wall_forces();  // collective, summed over ranks
    for (std::size_t k = 0; k < prims.size(); ++k)
      if (prims[k].kind == WallPrimitive::Kind::plane && prims[k].normal.z > 0.99) floor -= wall_forces[k].z;
    q["floor_force_over_weight"] = floor / (weight * norm(dem_->gravity()));
  }

 private:
  // Collective: mean |v| over the bodies (an exact sum: the same on any rank count) and its peak.
  void track_mean_speed() {
    const ParticleStore& p = dem_->particles();
    ExactSum sums[2];
    for (std::size_t i = 0; i < p.owned; ++i) sums[0] += norm(p.vel(i)), sums[1] += 1.0;
    ExactSum::all_reduce(sums, decomp_->comm());
    mean_speed_ = sums[1].value() > 0 ? sums[0].value() / sums[1].value() : 0.0;
    peak_mean_speed_ = std::max(peak_mean_speed_, mean_speed_);
  }

  // Collective: the highest grain (largest centre height; ties to the lower id) moves down at less
  // than half the free-fall speed F g t: something below has stopped it.
  bool top_grain_landed(double t) const {
    const ParticleStore& p = dem_->particles();
    struct {
      double z;
      int rank;
    } local{-1e300, decomp_->rank()}, top;
    std::size_t best = 0;
    for (std::size_t i = 0; i < p.owned; ++i)
      if (p.x[3 * i + 2] > local.z || (p.x[3 * i + 2] == local.z && p.id[i] < p.id[best])) local.z = p.x[3 * i + 2], best = i;
    MPI_Allreduce(&local, &top, 1, MPI_DOUBLE_INT, MPI_MAXLOC, decomp_->comm());
    double down = 0;  // speed along gravity of the top grain
    if (top.rank == decomp_->rank()) down = dot(p.vel(best), gravity_) / norm(gravity_);
    MPI_Bcast(&down, 1, MPI_DOUBLE, top.rank, decomp_->comm());
    return down < 0.5 * fall_factor_ * norm(gravity_) * t;
  }

  double fall_factor_ = 1, after_landing_ = 0, landing_time_ = -1;
  double mean_speed_ = 0, peak_mean_speed_ = 0;
  Vec3 gravity_;
  int material_ = 0, shape_ = 0;
  Vec3 spacing_;
  bool aligned_ = false;
  long max_grains_ = 0;
  double diameter_ = 0, spread_ = 0, jitter_ = 0;
  SettleCriterion settle_;
  std::uint64_t seed_ = 0;
  Vec3 region_lo_, region_hi_;
  long counts_[3] = {0, 0, 0};
};

}  // namespace

std::unique_ptr<DemScene> make_deposition_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir) {
  return std::make_unique<DepositionScene>(root, comm, dir);
}

}  // namespace tessera
