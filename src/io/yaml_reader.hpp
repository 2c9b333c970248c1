#pragma once
// Internal helper over yaml-cpp: typed access to a YAML tree with error messages that name the file,
// the line and the key path, and rejection of unknown keys. Not part of the public API (yaml-cpp stays
// a private dependency).

#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

namespace jointsim::io {

class YamlValue {
 public:
  /// Parses a file; throws InputError "FILE:LINE:COL: YAML syntax error: ..." on failure.
  static YamlValue loadFile(const std::string& path);
  /// Parses a string (for tests and inline documents); `name` stands for the file name in errors.
  static YamlValue loadString(const std::string& text, const std::string& name);

  YamlValue(YAML::Node node, std::string path, std::shared_ptr<const std::string> file, int line);

  bool defined() const { return node_.IsDefined() && !node_.IsNull(); }
  bool isMap() const { return node_.IsMap(); }
  bool isSequence() const { return node_.IsSequence(); }
  bool has(const std::string& key) const;
  /// Child by key. Missing children are returned undefined, carrying the parent's line.
  YamlValue operator[](const std::string& key) const;
  /// Child by key; throws "missing required key" (with `what`, e.g. "mass in kg") if absent.
  YamlValue required(const std::string& key, const std::string& what) const;
  YamlValue at(size_t index) const;
  size_t size() const;
  std::vector<std::string> keys() const;

  void expectMap(const std::string& what) const;
  void expectSequence(const std::string& what) const;
  /// Throws on any key not in `allowed`, suggesting the closest allowed key.
  void allowKeys(std::initializer_list<const char*> allowed) const;

  double asDouble(const std::string& what = "a number") const;
  double asDouble(double fallback, const std::string& what) const;  // fallback when undefined
  long asInt(const std::string& what = "an integer") const;
  bool asBool(const std::string& what = "true or false") const;
  std::string asString(const std::string& what = "a string") const;
  std::string asString(const std::string& fallback, const std::string& what) const;
  std::vector<double> asDoubles(size_t expected_size, const std::string& what) const;  // 0 = any size
  Eigen::Vector3d asVector3(const std::string& what) const;
  /// A file path; a relative one is resolved against the directory of the YAML file it appears in.
  std::string asPath(const std::string& what = "a file path") const;

  const std::string& path() const { return path_; }
  const std::string& file() const { return *file_; }
  int line() const { return line_; }
  const YAML::Node& node() const { return node_; }

  /// "FILE:LINE: PATH: MESSAGE" as an InputError.
  [[noreturn]] void fail(const std::string& message) const;
  /// "FILE:LINE: PATH: expected WHAT, got VALUE".
  [[noreturn]] void failExpected(const std::string& what) const;

 private:
  YAML::Node node_;
  std::string path_;
  std::shared_ptr<const std::string> file_;
  int line_;  // 1-based, 0 if unknown
};

/// Closest string in `candidates` to `word` by edit distance, or "" when nothing is close.
std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace jointsim::io
