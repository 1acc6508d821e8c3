// SPDX-License-Identifier: MIT
// The resolved case (YAML) as JSON, for summary.json: numbers stay numbers.
#pragma once
#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>

namespace tessera {
nlohmann::json yaml_to_json(const YAML::Node& n);
}
