#include "jointsim/io/json.hpp"

#include <cmath>
#include <cstdio>

namespace jointsim::io {

std::string JsonWriter::quote(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (static_cast<unsigned char>(ch) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(ch)));
          out += buf;
        } else {
          out += ch;
        }
    }
  }
  return out + "\"";
}

void JsonWriter::newline() {
  if (!pretty_) return;
  os_ << '\n' << std::string(2 * first_.size(), ' ');
}

void JsonWriter::separator() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!first_.empty()) {
    if (!first_.back()) os_ << ',';
    first_.back() = false;
    newline();
  }
}

void JsonWriter::beginObject() {
  separator();
  os_ << '{';
  first_.push_back(true);
}

void JsonWriter::endObject() {
  const bool empty = first_.back();
  first_.pop_back();
  if (!empty) newline();
  os_ << '}';
  if (first_.empty() && pretty_) os_ << '\n';
}

void JsonWriter::beginArray() {
  separator();
  os_ << '[';
  first_.push_back(true);
}

void JsonWriter::endArray() {
  first_.pop_back();
  os_ << ']';
}

void JsonWriter::key(const std::string& k) {
  separator();
  os_ << quote(k) << (pretty_ ? ": " : ":");
  after_key_ = true;
}

void JsonWriter::value(double x) {
  separator();
  if (!std::isfinite(x)) {
    os_ << "null";
    return;
  }
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  os_ << buf;
}

void JsonWriter::value(long x) {
  separator();
  os_ << x;
}

void JsonWriter::value(bool x) {
  separator();
  os_ << (x ? "true" : "false");
}

void JsonWriter::value(const std::string& s) {
  separator();
  os_ << quote(s);
}

void JsonWriter::null() {
  separator();
  os_ << "null";
}

void JsonWriter::value(const Eigen::Ref<const Eigen::VectorXd>& v) {
  const bool pretty = pretty_;
  pretty_ = false;  // keep numeric arrays on one line
  beginArray();
  for (Eigen::Index i = 0; i < v.size(); ++i) value(v[i]);
  endArray();
  pretty_ = pretty;
}

void JsonWriter::valueRows(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  beginArray();
  for (Eigen::Index r = 0; r < m.rows(); ++r) value(Eigen::VectorXd(m.row(r).transpose()));
  endArray();
}

}  // namespace jointsim::io
