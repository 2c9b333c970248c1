#pragma once
/// \file
/// A small binary format for snapshots of a simulation's state (sim::Simulator::saveState): little-endian
/// fixed-size fields written in order and read back in the same order. A reader that runs out of bytes, or
/// finds a count or tag other than expected, throws InputError naming what it was reading, so that a truncated
/// or foreign byte string is refused with a clear message instead of being half-applied.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointsim {

class ByteWriter {
 public:
  void u64(std::uint64_t v);
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v);  ///< bit for bit (NaN payloads and signed zeros kept)
  void boolean(bool v) { u64(v ? 1U : 0U); }
  void text(const std::string& s);  ///< length, then the bytes
  void vector(const Eigen::Ref<const Eigen::VectorXd>& v);
  void doubles(const std::vector<double>& v);
  void flags(const std::vector<char>& v);
  /// A tag that the reader checks (e.g. the name of the component whose fields follow).
  void tag(const std::string& name) { text(name); }
  const std::string& bytes() const { return out_; }
  std::string release() { return std::move(out_); }

 private:
  std::string out_;
};

class ByteReader {
 public:
  /// Reads `bytes` (not copied: must outlive the reader); `what` names the byte string in messages.
  ByteReader(const std::string& bytes, std::string what) : in_(bytes), what_(std::move(what)) {}
  std::uint64_t u64(const char* field);
  std::int64_t i64(const char* field) { return static_cast<std::int64_t>(u64(field)); }
  double f64(const char* field);
  bool boolean(const char* field);
  std::string text(const char* field);
  /// A vector of exactly `size` entries (InputError otherwise); size < 0: any size.
  Eigen::VectorXd vector(const char* field, Eigen::Index size = -1);
  std::vector<double> doubles(const char* field, long size = -1);
  std::vector<char> flags(const char* field, long size = -1);
  /// Checks that the next field is the tag `name` (InputError naming both otherwise).
  void tag(const std::string& name);
  /// InputError unless every byte was read.
  void finish() const;
  [[noreturn]] void fail(const std::string& message) const;

 private:
  void need(std::size_t n, const char* field);
  std::uint64_t count(const char* field, long expected);
  const std::string& in_;
  std::string what_;
  std::size_t pos_ = 0;
};

}  // namespace jointsim
