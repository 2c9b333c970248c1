#include "jointsim/common/bytes.hpp"

#include <cstring>

#include "jointsim/common/error.hpp"

namespace jointsim {

void ByteWriter::u64(std::uint64_t v) {
  char b[8];
  for (int i = 0; i < 8; ++i) b[i] = static_cast<char>((v >> (8 * i)) & 0xFFU);
  out_.append(b, 8);
}

void ByteWriter::f64(double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  u64(bits);
}

void ByteWriter::text(const std::string& s) {
  u64(s.size());
  out_.append(s);
}

void ByteWriter::vector(const Eigen::Ref<const Eigen::VectorXd>& v) {
  u64(static_cast<std::uint64_t>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) f64(v[i]);
}

void ByteWriter::doubles(const std::vector<double>& v) {
  u64(v.size());
  for (double x : v) f64(x);
}

void ByteWriter::flags(const std::vector<char>& v) {
  u64(v.size());
  out_.append(v.begin(), v.end());
}

void ByteReader::fail(const std::string& message) const {
  throw InputError(what_ + ": " + message + " (at byte " + std::to_string(pos_) + " of " + std::to_string(in_.size()) +
                   ")");
}

void ByteReader::need(std::size_t n, const char* field) {
  if (in_.size() - pos_ < n)
    fail(std::string("truncated: ") + std::to_string(n) + " more bytes expected for '" + field + "'");
}

std::uint64_t ByteReader::u64(const char* field) {
  need(8, field);
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i)
    v |= static_cast<std::uint64_t>(static_cast<unsigned char>(in_[pos_ + static_cast<std::size_t>(i)])) << (8 * i);
  pos_ += 8;
  return v;
}

double ByteReader::f64(const char* field) {
  const std::uint64_t bits = u64(field);
  double v = 0.0;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

bool ByteReader::boolean(const char* field) {
  const std::uint64_t v = u64(field);
  if (v > 1U) fail(std::string("'") + field + "': expected 0 or 1, got " + std::to_string(v));
  return v == 1U;
}

std::uint64_t ByteReader::count(const char* field, long expected) {
  const std::uint64_t n = u64(field);
  if (expected >= 0 && n != static_cast<std::uint64_t>(expected))
    fail(std::string("'") + field + "' has " + std::to_string(n) + " entries, expected " + std::to_string(expected));
  if (n > in_.size() - pos_) fail(std::string("'") + field + "': a count of " + std::to_string(n) + " beyond the end");
  return n;
}

std::string ByteReader::text(const char* field) {
  const std::uint64_t n = count(field, -1);
  std::string s = in_.substr(pos_, n);
  pos_ += n;
  return s;
}

Eigen::VectorXd ByteReader::vector(const char* field, Eigen::Index size) {
  const std::uint64_t n = count(field, static_cast<long>(size));
  Eigen::VectorXd v(static_cast<Eigen::Index>(n));
  for (Eigen::Index i = 0; i < v.size(); ++i) v[i] = f64(field);
  return v;
}

std::vector<double> ByteReader::doubles(const char* field, long size) {
  const std::uint64_t n = count(field, size);
  std::vector<double> v(n);
  for (double& x : v) x = f64(field);
  return v;
}

std::vector<char> ByteReader::flags(const char* field, long size) {
  const std::uint64_t n = count(field, size);
  std::vector<char> v(in_.begin() + static_cast<std::ptrdiff_t>(pos_),
                      in_.begin() + static_cast<std::ptrdiff_t>(pos_ + n));
  pos_ += n;
  return v;
}

void ByteReader::tag(const std::string& name) {
  const std::size_t at = pos_;
  const std::string got = text("tag");
  if (got != name) {
    pos_ = at;
    fail("expected the part '" + name + "', found '" + got.substr(0, 80) + "'");
  }
}

void ByteReader::finish() const {
  if (pos_ != in_.size()) fail(std::to_string(in_.size() - pos_) + " bytes left over after the last field");
}

}  // namespace jointsim
