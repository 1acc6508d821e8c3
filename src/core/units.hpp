// SPDX-License-Identifier: MIT
// Units on entry: a case file value is either a bare number (SI) or "number unit" (e.g. "0.6 mm").
// The parser converts to SI once; everything inside Tessera is SI.
#pragma once
#include <optional>
#include <string>

namespace tessera {

// Physical dimension a key expects, spelt as its SI unit.
enum class Dim {
  none,               // dimensionless
  length,             // m
  time,               // s
  mass,               // kg
  density,            // kg/m^3
  pressure,           // Pa
  stiffness,          // N/m
  velocity,           // m/s
  acceleration,       // m/s^2
  energy,             // J
  damping,            // N s/m
  rate,               // 1/s
  angular_velocity,   // rad/s
  moment,             // N m
  moment_of_inertia,  // kg m^2
  viscosity,          // Pa s (dynamic)
  stiffness_per_area,  // N/m^3 (springs per unit area of a bonded face)
  damping_per_area,    // N s/m^3
  energy_per_area,     // J/m^2 (fracture energy)
};

const char* si_unit(Dim d);

// Parses "value [unit]" for dimension d. Returns nullopt when the text is not a number with a unit
// of that dimension; the caller turns that into an InputError naming the key.
std::optional<double> parse_quantity(const std::string& text, Dim d);

// Units accepted for d, for error messages ("m, mm, um, cm").
std::string accepted_units(Dim d);

}  // namespace tessera
