#pragma once
/// \file
/// Typed access to a YAML document with error messages that name the file, the line and the key path, and
/// rejection of unknown keys: what every jointsim file loader (robots, drives, experiments, sweeps) reads
/// through, and what a user's own experiment type reads its file with (experiments/registry.hpp). yaml-cpp
/// stays a private dependency: its nodes are behind the value's implementation.
///
///   const YamlValue root = YamlValue::loadFile("rig.yaml");
///   root.allowKeys({"mass", "stiffness"});
///   const double m = root.required("mass", "mass in kg").asDouble("a mass in kg");   // "rig.yaml:3: mass: ..."

#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/common/error.hpp"

namespace jointsim::io {

class YamlValue {
 public:
  /// Parses a file (read through io::readInputFile, so it is recorded as an input of the run); throws
  /// InputError "FILE:LINE:COL: YAML syntax error: ..." on failure.
  static YamlValue loadFile(const std::string& path);
  /// Parses a string (for tests and inline documents); `name` stands for the file name in errors.
  static YamlValue loadString(const std::string& text, const std::string& name);

  bool defined() const;  ///< present and not null
  bool isMap() const;
  bool isSequence() const;
  bool isScalar() const;
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
  /// The scalar's text as written (InputError naming `what` when not a scalar).
  std::string scalarText(const std::string& what) const;

  const std::string& path() const;  ///< key path from the document root ("" for the root)
  const std::string& file() const;  ///< the file name (or the name given to loadString)
  int line() const;                 ///< 1-based line of the value (or of its parent when missing)

  /// "FILE:LINE: PATH: MESSAGE" as an InputError.
  [[noreturn]] void fail(const std::string& message) const;
  /// "FILE:LINE: PATH: expected WHAT, got VALUE".
  [[noreturn]] void failExpected(const std::string& what) const;
  /// Re-throws an error of a parameter check (common/check.hpp) at its key below this value: the key path
  /// "positive.alpha0" or "tau_pos[2]" is looked up here (failing that, its last components), so the message
  /// names the file, the line and the full key path. An error that already names a file is re-thrown as is.
  [[noreturn]] void relocate(const InputError& error) const;
  /// Runs `check` (e.g. the validate() of a struct read from this value) and re-throws an InputError it throws
  /// at its key below this value (relocate).
  template <class Check>
  void validate(Check&& check) const {
    try {
      check();
    } catch (const InputError& e) {
      relocate(e);
    }
  }

  struct Impl;  ///< the yaml-cpp node and its location (src/io/yaml_node.hpp)
  explicit YamlValue(std::shared_ptr<const Impl> impl);
  const Impl& impl() const { return *impl_; }

 private:
  std::shared_ptr<const Impl> impl_;
};

/// Closest string in `candidates` to `word` by edit distance, or "" when nothing is close.
std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace jointsim::io
