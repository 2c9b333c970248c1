#include "io/yaml_reader.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "jointsim/common/error.hpp"

namespace jointsim::io {
namespace {

int lineOf(const YAML::Node& node, int fallback) {
  if (!node.IsDefined()) return fallback;
  const YAML::Mark mark = node.Mark();
  return mark.line >= 0 ? mark.line + 1 : fallback;
}

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list of " + std::to_string(node.size()) + " items";
  if (node.IsMap()) return "a mapping";
  return "an unknown node";
}

size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

}  // namespace

std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_d = std::max<size_t>(2, word.size() / 3) + 1;
  for (const auto& c : candidates) {
    const size_t d = editDistance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

YamlValue YamlValue::loadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open file for reading");
  std::stringstream ss;
  ss << in.rdbuf();
  return loadString(ss.str(), path);
}

YamlValue YamlValue::loadString(const std::string& text, const std::string& name) {
  auto file = std::make_shared<const std::string>(name);
  try {
    YAML::Node root = YAML::Load(text);
    return YamlValue(root, "", file, 1);
  } catch (const YAML::Exception& e) {
    std::ostringstream os;
    os << name << ":" << e.mark.line + 1 << ":" << e.mark.column + 1 << ": YAML syntax error: " << e.msg;
    throw InputError(os.str());
  }
}

YamlValue::YamlValue(YAML::Node node, std::string path, std::shared_ptr<const std::string> file, int line)
    : node_(std::move(node)), path_(std::move(path)), file_(std::move(file)), line_(lineOf(node_, line)) {}

bool YamlValue::has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined(); }

YamlValue YamlValue::operator[](const std::string& key) const {
  const std::string child_path = path_.empty() ? key : path_ + "." + key;
  if (!node_.IsMap()) return YamlValue(YAML::Node(YAML::NodeType::Undefined), child_path, file_, line_);
  const YAML::Node child = node_[key];
  return YamlValue(child, child_path, file_, line_);
}

YamlValue YamlValue::required(const std::string& key, const std::string& what) const {
  if (!node_.IsMap()) failExpected("a mapping with key '" + key + "'");
  YamlValue child = (*this)[key];
  if (!child.node_.IsDefined() || child.node_.IsNull())
    fail("missing required key '" + key + "' (" + what + ")");
  return child;
}

YamlValue YamlValue::at(size_t index) const {
  return YamlValue(node_[index], path_ + "[" + std::to_string(index) + "]", file_, line_);
}

size_t YamlValue::size() const { return node_.size(); }

std::vector<std::string> YamlValue::keys() const {
  std::vector<std::string> out;
  if (!node_.IsMap()) return out;
  for (const auto& kv : node_) out.push_back(kv.first.as<std::string>());
  return out;
}

void YamlValue::expectMap(const std::string& what) const {
  if (!node_.IsMap()) failExpected(what);
}

void YamlValue::expectSequence(const std::string& what) const {
  if (!node_.IsSequence()) failExpected(what);
}

void YamlValue::allowKeys(std::initializer_list<const char*> allowed) const {
  if (!node_.IsMap()) return;
  std::vector<std::string> names(allowed.begin(), allowed.end());
  for (const auto& kv : node_) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(names.begin(), names.end(), key) != names.end()) continue;
    std::string msg = "unknown key '" + key + "'";
    if (const std::string near = closestMatch(key, names); !near.empty())
      msg += " (did you mean '" + near + "'?)";
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    msg += "; allowed keys here: " + list;
    const std::string key_path = path_.empty() ? key : path_ + "." + key;
    throw InputError(*file_ + ":" + std::to_string(lineOf(kv.first, line_)) + ": " + key_path + ": " + msg);
  }
}

double YamlValue::asDouble(const std::string& what) const {
  if (!node_.IsScalar()) failExpected(what);
  double v = 0.0;
  try {
    v = node_.as<double>();
  } catch (const YAML::Exception&) {
    failExpected(what);
  }
  if (!std::isfinite(v)) failExpected(what + " (finite)");
  return v;
}

double YamlValue::asDouble(double fallback, const std::string& what) const {
  return defined() ? asDouble(what) : fallback;
}

long YamlValue::asInt(const std::string& what) const {
  if (!node_.IsScalar()) failExpected(what);
  try {
    return node_.as<long>();
  } catch (const YAML::Exception&) {
    failExpected(what);
  }
}

bool YamlValue::asBool(const std::string& what) const {
  if (!node_.IsScalar()) failExpected(what);
  try {
    return node_.as<bool>();
  } catch (const YAML::Exception&) {
    failExpected(what);
  }
}

std::string YamlValue::asString(const std::string& what) const {
  if (!node_.IsScalar()) failExpected(what);
  return node_.Scalar();
}

std::string YamlValue::asString(const std::string& fallback, const std::string& what) const {
  return defined() ? asString(what) : fallback;
}

std::vector<double> YamlValue::asDoubles(size_t expected_size, const std::string& what) const {
  if (!node_.IsSequence() || (expected_size != 0 && node_.size() != expected_size)) failExpected(what);
  std::vector<double> out;
  out.reserve(node_.size());
  for (size_t i = 0; i < node_.size(); ++i) out.push_back(at(i).asDouble("a number (" + what + ")"));
  return out;
}

Eigen::Vector3d YamlValue::asVector3(const std::string& what) const {
  const auto v = asDoubles(3, what);
  return {v[0], v[1], v[2]};
}

std::string YamlValue::asPath(const std::string& what) const {
  std::filesystem::path p = asString(what);
  if (p.is_relative()) p = std::filesystem::path(*file_).parent_path() / p;
  return p.lexically_normal().string();
}

void YamlValue::fail(const std::string& message) const {
  throw InputError(*file_ + ":" + std::to_string(line_) + ": " + (path_.empty() ? "(document)" : path_) +
                   ": " + message);
}

void YamlValue::failExpected(const std::string& what) const { fail("expected " + what + ", got " + describe(node_)); }

}  // namespace jointsim::io
