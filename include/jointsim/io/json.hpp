#pragma once
/// \file
/// Minimal JSON writer for results (numbers with 17 significant digits, so doubles round-trip).
/// Non-finite numbers are written as null (JSON has no inf/NaN).

#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointsim::io {

/// Streams a JSON document with automatic commas. Usage:
///   JsonWriter w(os); w.beginObject(); w.key("tau"); w.value(vec); w.endObject();
class JsonWriter {
 public:
  explicit JsonWriter(std::ostream& os, bool pretty = false) : os_(os), pretty_(pretty) {}
  void beginObject();
  void endObject();
  void beginArray();
  void endArray();
  void key(const std::string& k);
  void value(double x);
  void value(long x);
  void value(int x) { value(static_cast<long>(x)); }
  void value(bool x);
  void value(const std::string& s);
  void value(const char* s) { value(std::string(s)); }
  void value(const Eigen::Ref<const Eigen::VectorXd>& v);           ///< array of numbers
  void valueRows(const Eigen::Ref<const Eigen::MatrixXd>& m);       ///< array of row arrays
  void null();

  /// JSON string literal with escapes.
  static std::string quote(const std::string& s);

 private:
  void separator();
  void newline();
  std::ostream& os_;
  bool pretty_;
  std::vector<bool> first_;  // per open container: no element written yet
  bool after_key_ = false;
};

}  // namespace jointsim::io
