// SPDX-License-Identifier: MIT
// The drop-impact scene's own parts (drop-impact seed; issue 16), used by the coupled scene when the
// case has the sections below. Sizes with units; each key is listed in cases/drop_on_sand/README.md.
//
//   drop     the water drop, placed over the bed once the bodies exist: a sphere or a spheroid of
//            equivalent_diameter (its volume's sphere), aspect_ratio D_H / D_V, falling at velocity,
//            its centre centre_above_bed (the seed's h_w) above the bed's top H_s (the highest grain
//            top within bed_top_radius of the axis). The axis is the box's vertical centre line.
//   crater   the smoothed surface and the crater volume (analysis/bed_surface.hpp, theory D1-D6):
//            cell (Delta x*), ring_width (dr), surface_layer, max_radius; porosity_height: the bed's
//            porosity is reported below it. Measured at every snapshot (DIR/crater.csv) and at the
//            end (summary.json, DIR/crater_rings.csv, DIR/crater_surface.csv).
#pragma once
#include <cstdint>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "analysis/bed_surface.hpp"
#include "core/config.hpp"
#include "solid/dem_io.hpp"

namespace tessera {

class DemSolver;

// The drop as an ellipsoid of liquid.
struct DropShape {
  Vec3 centre, semi_axes, velocity;
};

class DropOnBed {
 public:
  // Reads section `drop` (liquid density: the fluid's, for the reported mass and momentum).
  DropOnBed(const ConfigNode& drop, const Vec3& box_lo, const Vec3& box_hi, double liquid_density);
  // Collective: measures the bed's top and places the drop above it (fails on a drop that would
  // start in the bed or outside the box).
  DropShape place(const DemSolver& dem);
  // The quantities of the start (bed top, drop size, mass, momentum) into summary.json and back
  // from a checkpoint's extras, so that a restarted run reports them too.
  void save(CheckpointExtras& e) const;
  void restore(const CheckpointExtras& e);
  void report(nlohmann::json& q) const;
  double bed_top_height() const { return bed_top_; }
  double axis_x() const { return cx_; }
  double axis_y() const { return cy_; }

 private:
  ConfigNode node_;
  Vec3 lo_, hi_;
  double cx_ = 0, cy_ = 0, diameter_ = 0, aspect_ = 1, speed_ = 0, above_ = 0, top_radius_ = 0, rho_ = 0;
  double bed_top_ = 0;
};

class CraterMonitor {
 public:
  // grain_length: the default ejection_distance.
  CraterMonitor(const ConfigNode& crater, const Vec3& box_lo, const Vec3& box_hi, double axis_x, double axis_y,
                double grain_length);
  // Collective: porosity below porosity_height (exact tetrahedron clipping).
  double porosity(const DemSolver& dem) const;
  // Collective: the crater now; rank 0 appends a row to DIR/crater.csv.
  void sample(const DemSolver& dem, double time);
  // Collective: the crater at the end into quantities; rank 0 writes the ring profile and surface.
  void finish(const DemSolver& dem, nlohmann::json& q);
  void open(const std::string& dir, bool append, bool root);
  // Where the bodies started (the bed file), for the count of grains that end more than
  // ejection_distance from there (`displaced_grains`: the ejected grains and those the crater's
  // wall let slide); empty: no count.
  void set_start_positions(std::map<std::int64_t, Vec3> x) { start_ = std::move(x); }
  // Collective, a fresh run's start: the bed's porosity before the drop.
  void start(const DemSolver& dem) { porosity_start_ = porosity(dem); }
  // The start's measures (porosity; the first sample's crater volume, the method's reading of the
  // bed before the drop) into a checkpoint's extras and back.
  void save(CheckpointExtras& e) const;
  void restore(const CheckpointExtras& e);

 private:
  CraterSettings s_;
  Vec3 lo_, hi_;
  double porosity_height_ = 0, ejection_distance_ = 0, porosity_start_ = 0;
  std::optional<double> start_volume_;  // a crater volume may be negative: no sentinel value
  std::map<std::int64_t, Vec3> start_;
  std::string dir_;
  std::ofstream csv_;
};

}  // namespace tessera
