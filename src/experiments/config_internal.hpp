#pragma once
// Internal: the parts of experiment-file handling that work on the yaml-cpp document itself.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "jointsim/drive/parameters.hpp"
#include "jointsim/io/yaml.hpp"

namespace jointsim::experiments::detail {

/// Applies `key.path=value` overrides to the document; throws InputError if a key does not exist.
void applyOverrides(const io::YamlValue& root, const std::vector<std::string>& overrides);
/// An override's key path split into its components: "a.b[2].c" or "a.b.2.c" -> {"a", "b", "2", "c"}.
std::vector<std::string> keyParts(const std::string& path);
/// Removes `key` from the mapping `map` (the document is shared: every value of it sees the change).
void removeKey(const io::YamlValue& map, const std::string& key);
/// A YAML value as JSON (scalars that parse as finite numbers or as booleans become numbers/booleans).
nlohmann::ordered_json yamlToJson(const io::YamlValue& value);
/// A key path with its list indices blanked: "trajectory.a[3][0]" -> "trajectory.a[][]".
std::string keyPattern(const std::string& key);
/// The unit of the keys every experiment type shares (duration, log_rate, solver.*, limits.*, joint_limits.*), ""
/// for another key.
std::string commonKeyUnit(const std::string& key);
/// The unit of `key` from a table of key patterns (keyPattern: indices blanked) and units, then the profiles at the
/// given prefixes (profileKeyUnit, with their value units), then the common keys; "" for a key none of them knows.
std::string patternKeyUnit(const std::string& key, const std::vector<std::pair<std::string, std::string>>& units,
                           const std::vector<std::pair<std::string, std::string>>& profiles = {});
/// The unit of the key pattern `pattern` (keyPattern) inside a profile mapping at `prefix` ("input.profile.") whose
/// values are in `unit`: value, initial, final, offset, amplitude, values[] in `unit`, slope in unit/s, times in s,
/// frequency in Hz, phase in rad; "" for another key.
std::string profileKeyUnit(const std::string& pattern, const std::string& prefix, const std::string& unit);
/// The unit of `key` in a component's parameter table, also for the symmetric friction keys (alpha0 for
/// positive.alpha0 and negative.alpha0); "" when the table has no such key.
std::string tableKeyUnit(const std::vector<drive::ParameterInfo>& table, const std::string& key);
/// A vector as a JSON array.
nlohmann::ordered_json vectorJson(const Eigen::Ref<const Eigen::VectorXd>& v);

}  // namespace jointsim::experiments::detail
