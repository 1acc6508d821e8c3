// SPDX-License-Identifier: MIT
// Case files: YAML, SI units (a value may carry a unit, converted on entry, see units.hpp).
//
// Modules read their own keys through ConfigNode; every read records the key as known and writes
// the value (in SI, defaults filled in) into the resolved case that summary.json keeps. After
// set-up, Config::check_unused() turns every key nobody read into an "unknown key" error, so a
// typo stops the run before any work. Every error names the key, the value and what is allowed.
#pragma once
#include <yaml-cpp/yaml.h>

#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/units.hpp"
#include "core/vec3.hpp"

namespace tessera {

// Allowed interval of a real value.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;

  static Range any() { return {}; }
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static Range non_negative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  static Range closed(double a, double b) { return {a, b, false, false}; }
  static Range half_open(double a, double b) { return {a, b, false, true}; }
  bool contains(double v) const;
  std::string describe(Dim d) const;
};

struct ConfigState;

class ConfigNode {
 public:
  ConfigNode(std::shared_ptr<ConfigState> state, YAML::Node in, YAML::Node out, std::string path);

  const std::string& path() const { return path_; }
  std::string key_path(const std::string& key) const;
  bool has(const std::string& key) const;
  bool is_list(const std::string& key) const;  // present and a sequence

  double real(const std::string& key, Dim dim, Range range) const;
  double real(const std::string& key, Dim dim, Range range, double fallback) const;
  long integer(const std::string& key, long lo, long hi) const;
  long integer(const std::string& key, long lo, long hi, long fallback) const;
  bool flag(const std::string& key, bool fallback) const;
  std::string text(const std::string& key) const;
  std::string text(const std::string& key, const std::string& fallback) const;
  std::string choice(const std::string& key, const std::vector<std::string>& allowed) const;
  std::string choice(const std::string& key, const std::vector<std::string>& allowed,
                     const std::string& fallback) const;
  Vec3 vec3(const std::string& key, Dim dim) const;
  Vec3 vec3(const std::string& key, Dim dim, const Vec3& fallback) const;
  std::vector<long> integers(const std::string& key, std::size_t count, long lo, long hi) const;
  std::vector<double> reals(const std::string& key, Dim dim) const;  // a list of any length (may be empty)
  std::vector<std::string> texts(const std::string& key) const;

  ConfigNode section(const std::string& key) const;  // required mapping
  std::optional<ConfigNode> optional_section(const std::string& key) const;
  std::vector<ConfigNode> list(const std::string& key) const;  // sequence of mappings (may be absent)
  std::vector<std::string> keys() const;                       // keys of this mapping

  // Throws InputError for this node's key with the given explanation (for inconsistencies).
  [[noreturn]] void fail(const std::string& key, const std::string& allowed) const;

 private:
  YAML::Node child(const std::string& key) const;
  double parse_real(const std::string& key, const YAML::Node& n, Dim dim, Range range) const;
  void mark(const std::string& key) const;

  std::shared_ptr<ConfigState> state_;
  YAML::Node in_;
  mutable YAML::Node out_;  // handle into the resolved tree; writing through it is the point
  std::string path_;
};

class Config {
 public:
  // Loads a case file and applies "a.b.c=value" overrides (value parsed as YAML).
  static Config load(const std::string& file, const std::vector<std::string>& overrides = {});
  static Config parse(const std::string& yaml_text, const std::vector<std::string>& overrides = {});

  ConfigNode root() const;
  // Every key in the file that no module read is an error ("unknown key").
  void check_unused() const;
  // The case as resolved: SI values, defaults filled in.
  YAML::Node resolved() const;

 private:
  std::shared_ptr<ConfigState> state_;
};

}  // namespace tessera
