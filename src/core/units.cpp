// SPDX-License-Identifier: MIT
#include "core/units.hpp"

#include <array>
#include <cstdlib>
#include <string_view>

namespace tessera {
namespace {

struct UnitEntry {
  std::string_view name;
  Dim dim;
  double factor;
};

constexpr std::array kUnits{
    UnitEntry{"m", Dim::length, 1.0},
    UnitEntry{"cm", Dim::length, 1e-2},
    UnitEntry{"mm", Dim::length, 1e-3},
    UnitEntry{"um", Dim::length, 1e-6},
    UnitEntry{"s", Dim::time, 1.0},
    UnitEntry{"ms", Dim::time, 1e-3},
    UnitEntry{"us", Dim::time, 1e-6},
    UnitEntry{"ns", Dim::time, 1e-9},
    UnitEntry{"kg", Dim::mass, 1.0},
    UnitEntry{"g", Dim::mass, 1e-3},
    UnitEntry{"kg/m^3", Dim::density, 1.0},
    UnitEntry{"g/cm^3", Dim::density, 1e3},
    UnitEntry{"Pa", Dim::pressure, 1.0},
    UnitEntry{"kPa", Dim::pressure, 1e3},
    UnitEntry{"MPa", Dim::pressure, 1e6},
    UnitEntry{"GPa", Dim::pressure, 1e9},
    UnitEntry{"N/m", Dim::stiffness, 1.0},
    UnitEntry{"kN/m", Dim::stiffness, 1e3},
    UnitEntry{"MN/m", Dim::stiffness, 1e6},
    UnitEntry{"GN/m", Dim::stiffness, 1e9},
    UnitEntry{"N/m^3", Dim::stiffness_per_area, 1.0},
    UnitEntry{"MN/m^3", Dim::stiffness_per_area, 1e6},
    UnitEntry{"GN/m^3", Dim::stiffness_per_area, 1e9},
    UnitEntry{"N*s/m^3", Dim::damping_per_area, 1.0},
    UnitEntry{"MN*s/m^3", Dim::damping_per_area, 1e6},
    UnitEntry{"J/m^2", Dim::energy_per_area, 1.0},
    UnitEntry{"N/m", Dim::energy_per_area, 1.0},
    UnitEntry{"m/s", Dim::velocity, 1.0},
    UnitEntry{"mm/s", Dim::velocity, 1e-3},
    UnitEntry{"m/s^2", Dim::acceleration, 1.0},
    UnitEntry{"J", Dim::energy, 1.0},
    UnitEntry{"mJ", Dim::energy, 1e-3},
    UnitEntry{"uJ", Dim::energy, 1e-6},
    UnitEntry{"nJ", Dim::energy, 1e-9},
    UnitEntry{"N*s/m", Dim::damping, 1.0},
    UnitEntry{"N.s/m", Dim::damping, 1.0},
    UnitEntry{"MN*s/m", Dim::damping, 1e6},
    UnitEntry{"1/s", Dim::rate, 1.0},
    UnitEntry{"rad/s", Dim::angular_velocity, 1.0},
    UnitEntry{"N*m", Dim::moment, 1.0},
    UnitEntry{"N.m", Dim::moment, 1.0},
    UnitEntry{"kg*m^2", Dim::moment_of_inertia, 1.0},
    UnitEntry{"kg.m^2", Dim::moment_of_inertia, 1.0},
    UnitEntry{"Pa*s", Dim::viscosity, 1.0},
    UnitEntry{"Pa.s", Dim::viscosity, 1.0},
    UnitEntry{"mPa*s", Dim::viscosity, 1e-3},
    UnitEntry{"mPa.s", Dim::viscosity, 1e-3},
};

}  // namespace

const char* si_unit(Dim d) {
  switch (d) {
    case Dim::none:
      return "1";
    case Dim::length:
      return "m";
    case Dim::time:
      return "s";
    case Dim::mass:
      return "kg";
    case Dim::density:
      return "kg/m^3";
    case Dim::pressure:
      return "Pa";
    case Dim::stiffness:
      return "N/m";
    case Dim::velocity:
      return "m/s";
    case Dim::acceleration:
      return "m/s^2";
    case Dim::energy:
      return "J";
    case Dim::damping:
      return "N*s/m";
    case Dim::rate:
      return "1/s";
    case Dim::angular_velocity:
      return "rad/s";
    case Dim::moment:
      return "N*m";
    case Dim::moment_of_inertia:
      return "kg*m^2";
    case Dim::viscosity:
      return "Pa*s";
    case Dim::stiffness_per_area:
      return "N/m^3";
    case Dim::damping_per_area:
      return "N*s/m^3";
    case Dim::energy_per_area:
      return "J/m^2";
  }
  return "?";
}

std::string accepted_units(Dim d) {
  std::string s;
  for (const auto& u : kUnits)
    if (u.dim == d) s += (s.empty() ? "" : ", ") + std::string(u.name);
  return s.empty() ? "no unit" : s;
}

std::optional<double> parse_quantity(const std::string& text, Dim d) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (end == begin) return std::nullopt;
  std::string_view rest(end);
  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  while (!rest.empty() && rest.back() == ' ') rest.remove_suffix(1);
  if (rest.empty()) return value;
  for (const auto& u : kUnits)
    if (u.dim == d && u.name == rest) return value * u.factor;
  return std::nullopt;
}

}  // namespace tessera
