// SPDX-License-Identifier: MIT
#include "solid/contact_model.hpp"

#include <cmath>
#include <numbers>

#include "core/errors.hpp"

namespace tessera {

namespace {

double effective_youngs(const Material& a, const Material& b) {
  return 1.0 / ((1 - a.poisson_ratio * a.poisson_ratio) / a.youngs_modulus +
                (1 - b.poisson_ratio * b.poisson_ratio) / b.youngs_modulus);
}

double effective_shear(const Material& a, const Material& b) {
  const double ga = a.youngs_modulus / (2 * (1 + a.poisson_ratio));
  const double gb = b.youngs_modulus / (2 * (1 + b.poisson_ratio));
  return 1.0 / ((2 - a.poisson_ratio) / ga + (2 - b.poisson_ratio) / gb);
}

}  // namespace

ContactModel::ContactModel(LawKind law, std::vector<Material> materials) : law_(law), materials_(std::move(materials)) {
  table_.assign(materials_.size() * materials_.size(), PairParams{});
  defined_.assign(table_.size(), false);
}

ContactModel::ContactModel(const ConfigNode& solid) {
  const ConfigNode mats = solid.section("materials");
  const ConfigNode contact = solid.section("contact");
  std::vector<std::string> names;
  for (const LawKind k : kAllLaws) names.push_back(with_law(k, [](auto law) { return std::string(law.name); }));
  const std::string law = contact.choice("law", names);
  for (const LawKind k : kAllLaws)
    if (law == names[static_cast<std::size_t>(k)]) law_ = k;
  const bool moduli = with_law(law_, [](auto l) { return decltype(l)::needs_elastic_moduli; });
  for (const auto& name : mats.keys()) {
    const ConfigNode m = mats.section(name);
    Material mat;
    mat.name = name;
    mat.density = m.real("density", Dim::density, Range::positive());
    if (moduli) {
      mat.youngs_modulus = m.real("youngs_modulus", Dim::pressure, Range::positive());
      mat.poisson_ratio = m.real("poisson_ratio", Dim::none, Range::half_open(-1.0, 0.5));
    }
    materials_.push_back(mat);
  }
  if (materials_.empty()) mats.fail("", "at least one material");
  table_.assign(materials_.size() * materials_.size(), PairParams{});
  defined_.assign(table_.size(), false);
  const auto pairs = contact.list("pairs");
  if (pairs.empty()) contact.fail("pairs", "a list of material pairs with their contact parameters");
  for (const auto& p : pairs) {
    const auto names = p.texts("materials");
    if (names.size() != 2) p.fail("materials", "a list of two material names");
    const int a = material_index(names[0], p.key_path("materials"));
    const int b = material_index(names[1], p.key_path("materials"));
    if (has_pair(a, b)) p.fail("materials", "a pair not listed before");
    set_pair(a, b, read_pair(p, a, b));
  }
}

const char* ContactModel::law_name() const {
  return with_law(law_, [](auto law) { return law.name; });
}

int ContactModel::material_index(const std::string& name, const std::string& key) const {
  std::string known;
  for (std::size_t i = 0; i < materials_.size(); ++i) {
    if (materials_[i].name == name) return static_cast<int>(i);
    known += (known.empty() ? "" : ", ") + materials_[i].name;
  }
  throw InputError(key, name, "a material defined in solid.materials (" + known + ")");
}

void ContactModel::set_pair(int a, int b, const PairParams& p) {
  const std::size_t n = materials_.size();
  table_[a * n + b] = table_[b * n + a] = p;
  defined_[a * n + b] = defined_[b * n + a] = true;
}

PairParams ContactModel::read_pair(const ConfigNode& node, int a, int b) const {
  return with_law(law_, [&](auto law) { return read_pair(law, node, a, b); });
}

PairParams ContactModel::read_pair(HertzMindlin, const ConfigNode& node, int a, int b) const {
  const double friction = node.real("friction", Dim::none, Range::non_negative());
  return hertz_mindlin_pair(materials_[a], materials_[b],
                            node.real("restitution", Dim::none, Range{0.0, 1.0, true, false}), friction);
}

PairParams ContactModel::read_pair(LinearSpringDashpot, const ConfigNode& node, int, int) const {
  PairParams p;
  p.friction = node.real("friction", Dim::none, Range::non_negative());
  p.normal_stiffness = node.real("normal_stiffness", Dim::stiffness, Range::positive());
  p.tangential_stiffness = node.real("tangential_stiffness", Dim::stiffness, Range::non_negative(), p.normal_stiffness);
  const bool by_e = node.has("restitution"), by_abs = node.has("normal_damping"),
             by_rate = node.has("normal_damping_rate");
  if (by_e + by_abs + by_rate != 1)
    node.fail("restitution", "exactly one of restitution, normal_damping (N*s/m) or normal_damping_rate (1/s)");
  if (by_e) {
    p.restitution = node.real("restitution", Dim::none, Range{0.0, 1.0, true, false});
    p.dn_zeta = linear_zeta_for_restitution(p.restitution);
  } else if (by_abs) {
    p.dn_abs = node.real("normal_damping", Dim::damping, Range::non_negative());
  } else {
    p.dn_rate = node.real("normal_damping_rate", Dim::rate, Range::non_negative());
  }
  if (node.has("tangential_damping") && node.has("tangential_damping_rate"))
    node.fail("tangential_damping", "only one of tangential_damping or tangential_damping_rate");
  if (node.has("tangential_damping")) {
    p.dt_abs = node.real("tangential_damping", Dim::damping, Range::non_negative());
  } else if (node.has("tangential_damping_rate")) {
    p.dt_rate = node.real("tangential_damping_rate", Dim::rate, Range::non_negative());
  } else {
    // The seed takes D_t = D_n; with a restitution, the same damping ratio on k_t. (Nothing goes to
    // the resolved case: re-running it must apply this same rule.)
    p.dt_abs = p.dn_abs, p.dt_rate = p.dn_rate, p.dt_zeta = p.dn_zeta;
  }
  return p;
}

PairParams ContactModel::hertz_mindlin_pair(const Material& a, const Material& b, double restitution, double friction) {
  PairParams p;
  p.e_star = effective_youngs(a, b);
  p.g_star = effective_shear(a, b);
  p.restitution = restitution;
  p.hertz_alpha = hertz_alpha_for_restitution(restitution);
  p.friction = friction;
  return p;
}

PairParams ContactModel::linear_pair(double kn, double kt, double restitution, double friction) {
  PairParams p;
  p.normal_stiffness = kn;
  p.tangential_stiffness = kt;
  p.restitution = restitution;
  p.dn_zeta = p.dt_zeta = linear_zeta_for_restitution(restitution);
  p.friction = friction;
  return p;
}

double ContactModel::contact_duration(int a, int b, double meff, double reff, double v) const {
  return with_law(law_, [&](auto law) { return law.contact_duration(pair(a, b), meff, reff, v); });
}

double ContactModel::linear_zeta_for_restitution(double e) {
  if (e >= 1.0) return 0.0;
  const double l = std::log(e);
  return -l / std::sqrt(std::numbers::pi * std::numbers::pi + l * l);
}

double ContactModel::hertz_restitution_for_alpha(double alpha) {
  // RK4 on y = (x, x'); the force is clamped to be repulsive (no adhesion from the dashpot).
  auto accel = [alpha](double x, double u) {
    if (x <= 0) return 0.0;
    return -std::max(0.0, x * std::sqrt(x) + alpha * std::sqrt(std::sqrt(x)) * u);
  };
  double x = 0, u = 1;
  const double h = 2e-4;
  for (int step = 0; step < 2000000; ++step) {
    const double k1x = u, k1u = accel(x, u);
    const double k2x = u + 0.5 * h * k1u, k2u = accel(x + 0.5 * h * k1x, u + 0.5 * h * k1u);
    const double k3x = u + 0.5 * h * k2u, k3u = accel(x + 0.5 * h * k2x, u + 0.5 * h * k2u);
    const double k4x = u + h * k3u, k4u = accel(x + h * k3x, u + h * k3u);
    x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    u += h / 6 * (k1u + 2 * k2u + 2 * k3u + k4u);
    if (x <= 0 && step > 0) return -u;
    // Leaving with the force clamped at zero: no force acts again, the rebound speed is final.
    if (u < 0 && accel(x, u) == 0.0) return -u;
  }
  return -u;
}

double ContactModel::hertz_alpha_for_restitution(double e) {
  if (e >= 1.0) return 0.0;
  double lo = 0.0, hi = 1.0;
  while (hertz_restitution_for_alpha(hi) > e) hi *= 2.0;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (hertz_restitution_for_alpha(mid) > e ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace tessera
