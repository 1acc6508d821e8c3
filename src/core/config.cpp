// SPDX-License-Identifier: MIT
#include "core/config.hpp"

#include <cmath>
#include <sstream>

#include "core/errors.hpp"

namespace tessera {

struct ConfigState {
  YAML::Node input;
  YAML::Node resolved;
  std::set<std::string> used;
};

namespace {

std::string show(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "";
  if (n.IsScalar()) return n.Scalar();
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

std::string fmt_number(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

}  // namespace

bool Range::contains(double v) const {
  if (!std::isfinite(v)) return false;
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

std::string Range::describe(Dim d) const {
  std::string unit = d == Dim::none ? "" : std::string(" ") + si_unit(d);
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi)
    return std::string("a number in ") + (lo_open ? "(" : "[") + fmt_number(lo) + ", " + fmt_number(hi) +
           (hi_open ? ")" : "]") + unit;
  if (has_lo) return std::string("a number ") + (lo_open ? "> " : ">= ") + fmt_number(lo) + unit;
  if (has_hi) return std::string("a number ") + (hi_open ? "< " : "<= ") + fmt_number(hi) + unit;
  return "a finite number" + unit;
}

ConfigNode::ConfigNode(std::shared_ptr<ConfigState> state, YAML::Node in, YAML::Node out, std::string path)
    : state_(std::move(state)), in_(in), out_(out), path_(std::move(path)) {}

std::string ConfigNode::key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

void ConfigNode::mark(const std::string& key) const { state_->used.insert(key_path(key)); }

YAML::Node ConfigNode::child(const std::string& key) const {
  if (!in_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  return in_[key];
}

bool ConfigNode::has(const std::string& key) const {
  const YAML::Node n = child(key);
  return n.IsDefined() && !n.IsNull();
}

bool ConfigNode::is_list(const std::string& key) const { return has(key) && child(key).IsSequence(); }

void ConfigNode::fail(const std::string& key, const std::string& allowed) const {
  throw InputError(key_path(key), show(child(key)), allowed);
}

double ConfigNode::parse_real(const std::string& key, const YAML::Node& n, Dim dim, Range range) const {
  const std::string expected =
      range.describe(dim) + (dim == Dim::none ? "" : " (units accepted: " + accepted_units(dim) + ")");
  if (!n.IsScalar()) throw InputError(key_path(key), show(n), expected);
  const auto v = parse_quantity(n.Scalar(), dim);
  if (!v || !range.contains(*v)) throw InputError(key_path(key), n.Scalar(), expected);
  return *v;
}

double ConfigNode::real(const std::string& key, Dim dim, Range range) const {
  mark(key);
  if (!has(key)) throw InputError(key_path(key), "", "is required: " + range.describe(dim));
  const double v = parse_real(key, child(key), dim, range);
  out_[key] = v;
  return v;
}

double ConfigNode::real(const std::string& key, Dim dim, Range range, double fallback) const {
  if (!has(key)) {
    mark(key);
    out_[key] = fallback;
    return fallback;
  }
  return real(key, dim, range);
}

long ConfigNode::integer(const std::string& key, long lo, long hi) const {
  mark(key);
  const std::string allowed = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  if (!has(key)) throw InputError(key_path(key), "", "is required: " + allowed);
  const YAML::Node n = child(key);
  long v = 0;
  try {
    if (!n.IsScalar()) throw YAML::Exception(YAML::Mark(), "");
    std::size_t used = 0;
    v = std::stol(n.Scalar(), &used);
    if (used != n.Scalar().size()) throw YAML::Exception(YAML::Mark(), "");
  } catch (const std::exception&) {
    throw InputError(key_path(key), show(n), allowed);
  }
  if (v < lo || v > hi) throw InputError(key_path(key), show(n), allowed);
  out_[key] = v;
  return v;
}

long ConfigNode::integer(const std::string& key, long lo, long hi, long fallback) const {
  if (!has(key)) {
    mark(key);
    out_[key] = fallback;
    return fallback;
  }
  return integer(key, lo, hi);
}

bool ConfigNode::flag(const std::string& key, bool fallback) const {
  mark(key);
  if (!has(key)) {
    out_[key] = fallback;
    return fallback;
  }
  const YAML::Node n = child(key);
  bool v = false;
  try {
    v = n.as<bool>();
  } catch (const std::exception&) {
    throw InputError(key_path(key), show(n), "true or false");
  }
  out_[key] = v;
  return v;
}

std::string ConfigNode::text(const std::string& key) const {
  mark(key);
  if (!has(key)) throw InputError(key_path(key), "", "is required: a string");
  const YAML::Node n = child(key);
  if (!n.IsScalar()) throw InputError(key_path(key), show(n), "a string");
  out_[key] = n.Scalar();
  return n.Scalar();
}

std::string ConfigNode::text(const std::string& key, const std::string& fallback) const {
  if (!has(key)) {
    mark(key);
    out_[key] = fallback;
    return fallback;
  }
  return text(key);
}

std::string ConfigNode::choice(const std::string& key, const std::vector<std::string>& allowed) const {
  mark(key);
  if (!has(key)) throw InputError(key_path(key), "", "is required: one of " + join(allowed));
  const YAML::Node n = child(key);
  if (n.IsScalar())
    for (const auto& a : allowed)
      if (a == n.Scalar()) {
        out_[key] = a;
        return a;
      }
  throw InputError(key_path(key), show(n), "one of " + join(allowed));
}

std::string ConfigNode::choice(const std::string& key, const std::vector<std::string>& allowed,
                               const std::string& fallback) const {
  if (!has(key)) {
    mark(key);
    out_[key] = fallback;
    return fallback;
  }
  return choice(key, allowed);
}

Vec3 ConfigNode::vec3(const std::string& key, Dim dim) const {
  mark(key);
  const std::string allowed = std::string("a list of 3 numbers in ") + si_unit(dim);
  if (!has(key)) throw InputError(key_path(key), "", "is required: " + allowed);
  const YAML::Node n = child(key);
  if (!n.IsSequence() || n.size() != 3) throw InputError(key_path(key), show(n), allowed);
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    const auto q = n[i].IsScalar() ? parse_quantity(n[i].Scalar(), dim) : std::nullopt;
    if (!q || !std::isfinite(*q)) throw InputError(key_path(key), show(n), allowed);
    v[i] = *q;
  }
  YAML::Node o(YAML::NodeType::Sequence);
  o.SetStyle(YAML::EmitterStyle::Flow);
  for (int i = 0; i < 3; ++i) o.push_back(v[i]);
  out_[key] = o;
  return v;
}

Vec3 ConfigNode::vec3(const std::string& key, Dim dim, const Vec3& fallback) const {
  if (!has(key)) {
    mark(key);
    YAML::Node o(YAML::NodeType::Sequence);
    o.SetStyle(YAML::EmitterStyle::Flow);
    for (int i = 0; i < 3; ++i) o.push_back(fallback[i]);
    out_[key] = o;
    return fallback;
  }
  return vec3(key, dim);
}

std::vector<double> ConfigNode::reals(const std::string& key, Dim dim) const {
  mark(key);
  const std::string allowed = std::string("a list of numbers in ") + si_unit(dim);
  if (!has(key)) throw InputError(key_path(key), "", "is required: " + allowed);
  const YAML::Node n = child(key);
  if (!n.IsSequence()) throw InputError(key_path(key), show(n), allowed);
  std::vector<double> v;
  for (const auto& item : n) {
    const auto q = item.IsScalar() ? parse_quantity(item.Scalar(), dim) : std::nullopt;
    if (!q || !std::isfinite(*q)) throw InputError(key_path(key), show(n), allowed);
    v.push_back(*q);
  }
  YAML::Node o(YAML::NodeType::Sequence);
  o.SetStyle(YAML::EmitterStyle::Flow);
  for (double x : v) o.push_back(x);
  out_[key] = o;
  return v;
}

std::vector<long> ConfigNode::integers(const std::string& key, std::size_t count, long lo, long hi) const {
  mark(key);
  const std::string allowed =
      "a list of " + std::to_string(count) + " integers in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  const YAML::Node n = child(key);
  if (!n.IsSequence() || n.size() != count) throw InputError(key_path(key), show(n), allowed);
  std::vector<long> v;
  for (const auto& item : n) {
    try {
      v.push_back(item.as<long>());
    } catch (const std::exception&) {
      throw InputError(key_path(key), show(n), allowed);
    }
    if (v.back() < lo || v.back() > hi) throw InputError(key_path(key), show(n), allowed);
  }
  YAML::Node o(YAML::NodeType::Sequence);  // into the resolved case, which must run again as it is
  o.SetStyle(YAML::EmitterStyle::Flow);
  for (long x : v) o.push_back(x);
  out_[key] = o;
  return v;
}

std::vector<std::string> ConfigNode::texts(const std::string& key) const {
  mark(key);
  const YAML::Node n = child(key);
  std::vector<std::string> v;
  if (!n.IsDefined() || n.IsNull()) return v;
  if (!n.IsSequence()) throw InputError(key_path(key), show(n), "a list of strings");
  for (const auto& item : n) {
    if (!item.IsScalar()) throw InputError(key_path(key), show(n), "a list of strings");
    v.push_back(item.Scalar());
  }
  YAML::Node o(YAML::NodeType::Sequence);
  o.SetStyle(YAML::EmitterStyle::Flow);
  for (const auto& x : v) o.push_back(x);
  out_[key] = o;
  return v;
}

ConfigNode ConfigNode::section(const std::string& key) const {
  mark(key);
  const YAML::Node n = child(key);
  if (!n.IsDefined() || n.IsNull()) throw InputError(key_path(key), "", "is required: a section");
  if (!n.IsMap()) throw InputError(key_path(key), show(n), "a section (a mapping of keys)");
  return ConfigNode(state_, n, out_[key], key_path(key));
}

std::optional<ConfigNode> ConfigNode::optional_section(const std::string& key) const {
  if (!has(key)) {
    mark(key);
    return std::nullopt;
  }
  return section(key);
}

std::vector<ConfigNode> ConfigNode::list(const std::string& key) const {
  mark(key);
  std::vector<ConfigNode> items;
  const YAML::Node n = child(key);
  if (!n.IsDefined() || n.IsNull()) return items;
  if (!n.IsSequence()) throw InputError(key_path(key), show(n), "a list of sections");
  // A sequence in the resolved case (indexing a null node would make a mapping with keys 0, 1, ...,
  // which no case reads back).
  if (!out_[key].IsSequence()) out_[key] = YAML::Node(YAML::NodeType::Sequence);
  YAML::Node o = out_[key];
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string p = key_path(key) + "." + std::to_string(i);
    if (!n[i].IsMap()) throw InputError(p, show(n[i]), "a section (a mapping of keys)");
    state_->used.insert(p);
    while (o.size() <= i) o.push_back(YAML::Node(YAML::NodeType::Map));
    items.emplace_back(state_, n[i], o[i], p);
  }
  return items;
}

std::vector<std::string> ConfigNode::keys() const {
  std::vector<std::string> k;
  if (in_.IsMap())
    for (const auto& kv : in_) k.push_back(kv.first.Scalar());
  return k;
}

namespace {

void apply_override(YAML::Node root, const std::string& spec) {
  const auto eq = spec.find('=');
  if (eq == std::string::npos || eq == 0) throw InputError("--set", spec, "the form section.key=value");
  const std::string path = spec.substr(0, eq);
  YAML::Node value;
  try {
    value = YAML::Load(spec.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw InputError(path, spec.substr(eq + 1), std::string("a YAML value: ") + e.what());
  }
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const auto dot = path.find('.', start);
    parts.push_back(path.substr(start, dot - start));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  // yaml-cpp nodes are handles: walk by reassigning a handle chain kept alive in a vector.
  std::vector<YAML::Node> chain{root};
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node cur = chain.back();
    const std::string& part = parts[i];
    if (cur.IsSequence()) {
      const std::size_t idx = std::stoul(part);
      if (idx >= cur.size()) throw InputError(path, "", "index " + part + " is out of range");
      chain.push_back(cur[idx]);
    } else {
      if (!cur[part].IsDefined() || cur[part].IsNull()) cur[part] = YAML::Node(YAML::NodeType::Map);
      chain.push_back(cur[part]);
    }
  }
  YAML::Node last = chain.back();
  if (last.IsSequence()) {
    const std::size_t idx = std::stoul(parts.back());
    if (idx >= last.size()) throw InputError(path, "", "index out of range");
    last[idx] = value;
  } else {
    last[parts.back()] = value;
  }
}

Config finish(YAML::Node input, const std::vector<std::string>& overrides, const std::string& src,
              std::shared_ptr<ConfigState>& state) {
  if (!input.IsMap()) throw InputError("(case file)", src, "a YAML mapping of sections");
  for (const auto& o : overrides) apply_override(input, o);
  state = std::make_shared<ConfigState>();
  state->input = input;
  state->resolved = YAML::Node(YAML::NodeType::Map);
  return {};
}

void collect_unused(const YAML::Node& n, const std::string& path, const std::set<std::string>& used,
                    std::vector<std::string>& out) {
  if (n.IsMap()) {
    for (const auto& kv : n) {
      const std::string p = path.empty() ? kv.first.Scalar() : path + "." + kv.first.Scalar();
      if (!used.count(p))
        out.push_back(p);
      else
        collect_unused(kv.second, p, used, out);
    }
  } else if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i)
      if (used.count(path + "." + std::to_string(i))) collect_unused(n[i], path + "." + std::to_string(i), used, out);
  }
}

}  // namespace

Config Config::parse(const std::string& yaml_text, const std::vector<std::string>& overrides) {
  YAML::Node input;
  try {
    input = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw InputError("(case file)", "", std::string("valid YAML: ") + e.what());
  }
  Config c;
  finish(input, overrides, "(text)", c.state_);
  return c;
}

Config Config::load(const std::string& file, const std::vector<std::string>& overrides) {
  YAML::Node input;
  try {
    input = YAML::LoadFile(file);
  } catch (const YAML::BadFile&) {
    throw InputError("(case file)", file, "a readable YAML file");
  } catch (const YAML::Exception& e) {
    throw InputError("(case file)", file, std::string("valid YAML: ") + e.what());
  }
  Config c;
  finish(input, overrides, file, c.state_);
  return c;
}

ConfigNode Config::root() const { return ConfigNode(state_, state_->input, state_->resolved, ""); }

void Config::check_unused() const {
  std::vector<std::string> unused;
  collect_unused(state_->input, "", state_->used, unused);
  if (!unused.empty()) {
    std::string list;
    for (const auto& u : unused) list += (list.empty() ? "" : ", ") + u;
    throw InputError(
        unused.front(), "",
        "is not a key this scene reads (unknown keys: " + list + "); see the case README for the keys allowed");
  }
}

YAML::Node Config::resolved() const { return state_->resolved; }

}  // namespace tessera
