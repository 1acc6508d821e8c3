// SPDX-License-Identifier: MIT
// Materials and the material-pair table of contact parameters, built from the case file's
// `solid.materials` and `solid.contact` sections. The law (hooke | hertz_mindlin) is chosen by name
// from the registry below; the force loop is compiled once per law, never dispatched per contact.
#pragma once
#include <string>
#include <vector>

#include "core/config.hpp"
#include "solid/contact_laws.hpp"

namespace tessera {

struct Material {
  std::string name;
  double density = 0;
  double youngs_modulus = 0;  // Hertz-Mindlin only
  double poisson_ratio = 0;   // Hertz-Mindlin only
};

// The registry of contact laws: the one place a law is chosen by kind (at set-up, and once per
// block of contacts in the kernel; never per contact). with_law calls f with a value of the law's
// type; a new law is one enumerator here and one case below.
enum class LawKind { linear_spring_dashpot, hertz_mindlin };
template <class F>
decltype(auto) with_law(LawKind kind, F&& f) {
  switch (kind) {
    case LawKind::linear_spring_dashpot:
      return f(LinearSpringDashpot{});
    case LawKind::hertz_mindlin:
      return f(HertzMindlin{});
  }
  return f(LinearSpringDashpot{});  // unreachable: every kind is a case above
}
inline constexpr LawKind kAllLaws[] = {LawKind::linear_spring_dashpot, LawKind::hertz_mindlin};

class ContactModel {
 public:
  // Reads solid.materials and solid.contact.
  explicit ContactModel(const ConfigNode& solid);
  ContactModel(LawKind law, std::vector<Material> materials);

  LawKind law() const { return law_; }
  const char* law_name() const;
  const std::vector<Material>& materials() const { return materials_; }
  int material_index(const std::string& name, const std::string& key_for_errors) const;
  int material_count() const { return static_cast<int>(materials_.size()); }

  const PairParams& pair(int a, int b) const { return table_[a * materials_.size() + b]; }
  const PairParams* pair_table() const { return table_.data(); }  // pair(a, b) at a * material_count() + b
  bool has_pair(int a, int b) const { return defined_[a * materials_.size() + b]; }
  void set_pair(int a, int b, const PairParams& p);

  // Contact duration of two bodies of effective mass meff and radius reff meeting at speed v:
  // linear: pi / sqrt(k/m* - zeta-term^2); Hertz: 2.87 (m*^2 / (R* E*^2 v))^(1/5) (T6).
  double contact_duration(int a, int b, double meff, double reff, double v) const;

  // alpha for Hertz damping that gives restitution e (T2 with F_n >= 0), by bisection on the
  // dimensionless impact x'' = -max(0, x^(3/2) + alpha x^(1/4) x'), x(0) = 0, x'(0) = 1.
  static double hertz_alpha_for_restitution(double e);
  static double hertz_restitution_for_alpha(double alpha);
  // Pair parameters from material data (Hertz-Mindlin: E*, G* of T2) or from stiffnesses with a
  // restitution coefficient (linear, T5: the same damping ratio on k_n and k_t).
  static PairParams hertz_mindlin_pair(const Material& a, const Material& b, double restitution, double friction);
  static PairParams linear_pair(double kn, double kt, double restitution, double friction);
  // zeta of the linear spring-dashpot for restitution e: e = exp(-pi zeta / sqrt(1 - zeta^2)) (T5).
  static double linear_zeta_for_restitution(double e);

 private:
  PairParams read_pair(const ConfigNode& node, int a, int b) const;  // the law's keys
  PairParams read_pair(LinearSpringDashpot, const ConfigNode& node, int a, int b) const;
  PairParams read_pair(HertzMindlin, const ConfigNode& node, int a, int b) const;
  LawKind law_;
  std::vector<Material> materials_;
  std::vector<PairParams> table_;
  std::vector<bool> defined_;
};

}  // namespace tessera
