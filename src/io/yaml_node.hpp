#pragma once
// Internal: the yaml-cpp node behind an io::YamlValue, for the few places that work on the document itself
// (--set overrides, the document copied into summary.json). Not installed.
#include <memory>
#include <string>

#include <yaml-cpp/yaml.h>

#include "jointsim/io/yaml.hpp"

namespace jointsim::io {

struct YamlValue::Impl {
  YAML::Node node;
  std::string path;
  std::shared_ptr<const std::string> file;
  int line = 0;  // 1-based, 0 if unknown
};

/// The node of a value (shares the document: changes are seen by every value of it).
inline const YAML::Node& yamlNode(const YamlValue& v) { return v.impl().node; }

/// The text of a mapping key; InputError at `where` (file:line: path) for a key that is not a scalar
/// (`? [a, b]: 1` is valid YAML but no key jointsim knows).
std::string keyText(const YAML::Node& key, const YamlValue& where);

}  // namespace jointsim::io
