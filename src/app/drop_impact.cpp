// SPDX-License-Identifier: MIT
#include "app/drop_impact.hpp"

#include <mpi.h>

#include <cmath>
#include <numbers>
#include <sstream>

#include "core/text_file.hpp"
#include "solid/dem_solver.hpp"

namespace tessera {

DropOnBed::DropOnBed(const ConfigNode& drop, const Vec3& box_lo, const Vec3& box_hi, double liquid_density)
    : node_(drop), lo_(box_lo), hi_(box_hi), rho_(liquid_density) {
  cx_ = 0.5 * (lo_.x + hi_.x);
  cy_ = 0.5 * (lo_.y + hi_.y);
  diameter_ = drop.real("equivalent_diameter", Dim::length, Range::positive());
  aspect_ = drop.real("aspect_ratio", Dim::none, Range::closed(0.2, 5.0), 1.0);
  speed_ = drop.real("velocity", Dim::velocity, Range::non_negative());
  above_ = drop.real("centre_above_bed", Dim::length, Range::positive());
  top_radius_ = drop.real("bed_top_radius", Dim::length, Range::positive(), 1e-3);
}

DropShape DropOnBed::place(const DemSolver& dem) {
  bed_top_ = bed_top(grain_tops(dem), cx_, cy_, top_radius_);
  if (!std::isfinite(bed_top_))
    node_.fail("bed_top_radius", "a radius about the box's centre line that holds at least one grain's centre");
  // Equal volume: D_H^2 D_V = D^3 with D_H / D_V = aspect (the seed's Table 2 lists these halves).
  const double dv = diameter_ / std::cbrt(aspect_ * aspect_), dh = aspect_ * dv;
  DropShape d;
  d.semi_axes = {0.5 * dh, 0.5 * dh, 0.5 * dv};
  d.centre = {cx_, cy_, bed_top_ + above_};
  d.velocity = {0, 0, -speed_};
  if (above_ <= d.semi_axes.z)
    node_.fail("centre_above_bed", "more than the drop's vertical semi-axis (" + std::to_string(d.semi_axes.z) +
                                       " m): the drop would start in the bed");
  if (d.centre.z + d.semi_axes.z >= hi_.z || cx_ - d.semi_axes.x <= lo_.x || cy_ - d.semi_axes.y <= lo_.y)
    node_.fail("centre_above_bed", "a drop inside the box (its top at " + std::to_string(d.centre.z + d.semi_axes.z) +
                                       " m, the box's at " + std::to_string(hi_.z) + " m)");
  return d;
}

void DropOnBed::save(CheckpointExtras& e) const { e["drop_bed_top"] = bed_top_; }

void DropOnBed::restore(const CheckpointExtras& e) {
  if (auto it = e.find("drop_bed_top"); it != e.end()) bed_top_ = it->second;
}

void DropOnBed::report(nlohmann::json& q) const {
  const double mass = rho_ * std::numbers::pi / 6 * diameter_ * diameter_ * diameter_;
  const double dv = diameter_ / std::cbrt(aspect_ * aspect_);
  q["bed_top"] = bed_top_;  // the seed's H_s
  q["drop_mass"] = mass;
  q["drop_momentum"] = mass * speed_;  // kg m/s (1e-5 of g cm/s)
  q["drop_horizontal_diameter"] = aspect_ * dv;
  q["drop_vertical_diameter"] = dv;
  q["drop_velocity"] = speed_;
}

CraterMonitor::CraterMonitor(const ConfigNode& crater, const Vec3& box_lo, const Vec3& box_hi, double axis_x,
                             double axis_y, double grain_length)
    : lo_(box_lo), hi_(box_hi) {
  s_.cx = axis_x;
  s_.cy = axis_y;
  s_.cell = crater.real("cell", Dim::length, Range::positive());
  s_.ring_width = crater.real("ring_width", Dim::length, Range::positive());
  s_.surface_layer = crater.real("surface_layer", Dim::length, Range::positive());
  const double wall = std::min({axis_x - box_lo.x, box_hi.x - axis_x, axis_y - box_lo.y, box_hi.y - axis_y});
  s_.max_radius = crater.real("max_radius", Dim::length, Range::positive(), wall - s_.cell);
  if (s_.max_radius + 0.5 * s_.cell > wall)
    crater.fail("max_radius", "at most the distance from the axis to the nearest side wall less half a cell (" +
                                  std::to_string(wall - 0.5 * s_.cell) + " m)");
  if (s_.max_radius < 2 * s_.ring_width) crater.fail("max_radius", "at least two ring widths");
  porosity_height_ = crater.real("porosity_height", Dim::length, Range::positive(), 5e-3);
  ejection_distance_ = crater.real("ejection_distance", Dim::length, Range::positive(), grain_length);
  if (porosity_height_ > box_hi.z - box_lo.z) crater.fail("porosity_height", "at most the box's height");
}

double CraterMonitor::porosity(const DemSolver& dem) const {
  const double volume = (hi_.x - lo_.x) * (hi_.y - lo_.y) * porosity_height_;
  return 1 - solid_volume_below(dem, lo_.z + porosity_height_) / volume;
}

void CraterMonitor::open(const std::string& dir, bool append, bool root) {
  dir_ = dir;
  if (!root) return;
  csv_.open(dir + "/crater.csv", append ? std::ios::app : std::ios::trunc);
  if (!append)
    csv_ << "time,crater_volume,crater_depth,crater_rim_radius,crater_a,crater_b,section_volume,section_length_x,"
            "section_length_y,section_depth\n";
  csv_.precision(10);
}

void CraterMonitor::sample(const DemSolver& dem, double time) {
  const Crater c = measure_crater(grain_tops(dem), s_);
  if (!start_volume_) start_volume_ = c.volume;
  if (!csv_.is_open()) return;
  csv_ << time << ',' << c.volume << ',' << c.depth << ',' << c.rim_radius << ',' << c.a << ',' << c.b << ','
       << c.section_volume << ',' << c.section_x.length << ',' << c.section_y.length << ','
       << 0.5 * (c.section_x.depth() + c.section_y.depth()) << std::endl;
}

void CraterMonitor::save(CheckpointExtras& e) const {
  e["bed_porosity_start"] = porosity_start_;
  if (start_volume_) e["crater_volume_start"] = *start_volume_;
}

void CraterMonitor::restore(const CheckpointExtras& e) {
  if (auto it = e.find("bed_porosity_start"); it != e.end()) porosity_start_ = it->second;
  if (auto it = e.find("crater_volume_start"); it != e.end()) start_volume_ = it->second;
}

void CraterMonitor::finish(const DemSolver& dem, nlohmann::json& q) {
  const std::vector<GrainTop> tops = grain_tops(dem);
  const Crater c = measure_crater(tops, s_);
  q["crater_volume"] = c.volume;  // eq. 14, m^3
  q["crater_volume_start"] = start_volume_.value_or(c.volume);
  q["crater_depth"] = c.depth;    // H = a - b
  q["crater_rim_radius"] = c.rim_radius;  // L
  q["crater_a"] = c.a;
  q["crater_b"] = c.b;
  q["crater_valid"] = c.valid;
  q["crater_section_volume"] = c.section_volume;  // eq. 13
  q["crater_section"] = {{"a1_x", c.section_x.a1}, {"a2_x", c.section_x.a2}, {"b_x", c.section_x.b},
                         {"L1", c.section_x.length}, {"a1_y", c.section_y.a1}, {"a2_y", c.section_y.a2},
                         {"b_y", c.section_y.b}, {"L2", c.section_y.length}};
  q["crater_settings"] = {{"cell", s_.cell}, {"ring_width", s_.ring_width}, {"surface_layer", s_.surface_layer},
                          {"max_radius", s_.max_radius}, {"axis", {s_.cx, s_.cy}}};
  q["bed_porosity"] = porosity(dem);
  q["bed_porosity_start"] = porosity_start_;
  q["porosity_height"] = porosity_height_;
  if (!start_.empty()) {
    const ParticleStore& p = dem.particles();
    long moved = 0;
    for (std::size_t i = 0; i < p.owned; ++i)
      if (auto it = start_.find(p.id[i]); it != start_.end() && norm(p.pos(i) - it->second) > ejection_distance_) ++moved;
    MPI_Allreduce(MPI_IN_PLACE, &moved, 1, MPI_LONG, MPI_SUM, dem.decomposition().comm());
    q["displaced_grains"] = moved;
    q["ejection_distance"] = ejection_distance_;
  }
  if (dem.decomposition().rank() != 0) return;
  std::ostringstream rings;
  rings.precision(10);
  rings << "radius,height,cells\n";
  for (std::size_t k = 0; k < c.ring_radius.size(); ++k)
    rings << c.ring_radius[k] << ',' << c.ring_height[k] << ',' << c.ring_cells[k] << '\n';
  write_file_atomically(dir_ + "/crater_rings.csv", rings.str());
  std::ostringstream surf;
  surf.precision(10);
  surf << "x,y,height\n";
  const int w = 2 * c.n + 1;
  for (int j = -c.n; j <= c.n; ++j)
    for (int i = -c.n; i <= c.n; ++i)
      surf << s_.cx + i * s_.cell << ',' << s_.cy + j * s_.cell << ',' << c.height[std::size_t(j + c.n) * w + (i + c.n)]
           << '\n';
  write_file_atomically(dir_ + "/crater_surface.csv", surf.str());
}

}  // namespace tessera
