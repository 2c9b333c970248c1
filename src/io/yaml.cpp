#include "jointsim/io/yaml.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "io/yaml_node.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/io/input_files.hpp"

namespace jointsim::io {
namespace {

int lineOf(const YAML::Node& node, int fallback) {
  if (!node.IsDefined()) return fallback;
  const YAML::Mark mark = node.Mark();
  return mark.line >= 0 ? mark.line + 1 : fallback;
}

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + printable(node.Scalar(), 80) + "'";
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

YamlValue make(const YAML::Node& node, std::string path, std::shared_ptr<const std::string> file, int parent_line) {
  // Copy-constructed, never assigned: assigning a yaml-cpp node writes through to the document (and throws
  // for the zombie node of a missing key).
  const int line = lineOf(node, parent_line);
  return YamlValue(std::make_shared<YamlValue::Impl>(YamlValue::Impl{node, std::move(path), std::move(file), line}));
}

/// "a.b[2].c" -> {"a", "b", "[2]", "c"}.
std::vector<std::string> splitKeyPath(const std::string& path) {
  std::vector<std::string> parts;
  std::string cur;
  for (const char ch : path) {
    if (ch == '.' || ch == '[') {
      if (!cur.empty()) parts.push_back(cur);
      cur = ch == '[' ? "[" : "";
    } else if (ch == ']') {
      parts.push_back(cur + "]");
      cur.clear();
    } else {
      cur += ch;
    }
  }
  if (!cur.empty()) parts.push_back(cur);
  return parts;
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

std::string keyText(const YAML::Node& key, const YamlValue& where) {
  if (!key.IsScalar())
    throw InputError(where.file(), lineOf(key, where.line()), where.path().empty() ? "(document)" : where.path(),
                     "expected mapping keys that are names, got a key that is " + std::string(key.IsMap() ? "a mapping"
                                                                                              : key.IsSequence()
                                                                                                  ? "a list"
                                                                                                  : "empty"));
  return key.Scalar();
}

YamlValue::YamlValue(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

YamlValue YamlValue::loadFile(const std::string& path) { return loadString(readInputFile(path), path); }

YamlValue YamlValue::loadString(const std::string& text, const std::string& name) {
  auto file = std::make_shared<const std::string>(name);
  try {
    return make(YAML::Load(text), "", file, 1);
  } catch (const YAML::Exception& e) {
    std::ostringstream os;
    os << e.mark.line + 1 << ":" << e.mark.column + 1;
    throw InputError(name + ":" + os.str() + ": YAML syntax error: " + e.msg);
  }
}

bool YamlValue::defined() const { return impl_->node.IsDefined() && !impl_->node.IsNull(); }
bool YamlValue::isMap() const { return impl_->node.IsMap(); }
bool YamlValue::isSequence() const { return impl_->node.IsSequence(); }
bool YamlValue::isScalar() const { return impl_->node.IsScalar(); }
const std::string& YamlValue::path() const { return impl_->path; }
const std::string& YamlValue::file() const { return *impl_->file; }
int YamlValue::line() const { return impl_->line; }

bool YamlValue::has(const std::string& key) const { return impl_->node.IsMap() && impl_->node[key].IsDefined(); }

YamlValue YamlValue::operator[](const std::string& key) const {
  const std::string child_path = impl_->path.empty() ? key : impl_->path + "." + key;
  if (!impl_->node.IsMap()) return make(YAML::Node(YAML::NodeType::Undefined), child_path, impl_->file, impl_->line);
  const YAML::Node child = impl_->node[key];
  return make(child, child_path, impl_->file, impl_->line);
}

YamlValue YamlValue::required(const std::string& key, const std::string& what) const {
  if (!impl_->node.IsMap()) failExpected("a mapping with key '" + key + "'");
  YamlValue child = (*this)[key];
  if (!child.defined()) fail("missing required key '" + key + "' (" + what + ")");
  return child;
}

YamlValue YamlValue::at(size_t index) const {
  return make(impl_->node[index], impl_->path + "[" + std::to_string(index) + "]", impl_->file, impl_->line);
}

size_t YamlValue::size() const { return impl_->node.size(); }

std::vector<std::string> YamlValue::keys() const {
  std::vector<std::string> out;
  if (!impl_->node.IsMap()) return out;
  for (const auto& kv : impl_->node) out.push_back(keyText(kv.first, *this));
  return out;
}

void YamlValue::expectMap(const std::string& what) const {
  if (!impl_->node.IsMap()) failExpected(what);
}

void YamlValue::expectSequence(const std::string& what) const {
  if (!impl_->node.IsSequence()) failExpected(what);
}

void YamlValue::allowKeys(std::initializer_list<const char*> allowed) const {
  if (!impl_->node.IsMap()) return;
  std::vector<std::string> names(allowed.begin(), allowed.end());
  for (const auto& kv : impl_->node) {
    const std::string key = keyText(kv.first, *this);
    if (std::find(names.begin(), names.end(), key) != names.end()) continue;
    std::string msg = "unknown key '" + key + "'";
    if (const std::string near = closestMatch(key, names); !near.empty()) msg += " (did you mean '" + near + "'?)";
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    msg += "; allowed keys here: " + list;
    const std::string key_path = impl_->path.empty() ? key : impl_->path + "." + key;
    throw InputError(*impl_->file, lineOf(kv.first, impl_->line), key_path, msg);
  }
}

double YamlValue::asDouble(const std::string& what) const {
  if (!impl_->node.IsScalar()) failExpected(what);
  double v = 0.0;
  try {
    v = impl_->node.as<double>();
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
  if (!impl_->node.IsScalar()) failExpected(what);
  try {
    return impl_->node.as<long>();
  } catch (const YAML::Exception&) {
    failExpected(what);
  }
}

bool YamlValue::asBool(const std::string& what) const {
  if (!impl_->node.IsScalar()) failExpected(what);
  try {
    return impl_->node.as<bool>();
  } catch (const YAML::Exception&) {
    failExpected(what);
  }
}

std::string YamlValue::asString(const std::string& what) const {
  if (!impl_->node.IsScalar()) failExpected(what);
  return impl_->node.Scalar();
}

std::string YamlValue::asString(const std::string& fallback, const std::string& what) const {
  return defined() ? asString(what) : fallback;
}

std::string YamlValue::scalarText(const std::string& what) const {
  if (!defined() || !impl_->node.IsScalar()) failExpected(what);
  return impl_->node.Scalar();
}

std::vector<double> YamlValue::asDoubles(size_t expected_size, const std::string& what) const {
  if (!impl_->node.IsSequence() || (expected_size != 0 && impl_->node.size() != expected_size)) failExpected(what);
  std::vector<double> out;
  out.reserve(impl_->node.size());
  for (size_t i = 0; i < impl_->node.size(); ++i) out.push_back(at(i).asDouble("a number (" + what + ")"));
  return out;
}

Eigen::Vector3d YamlValue::asVector3(const std::string& what) const {
  const auto v = asDoubles(3, what);
  return {v[0], v[1], v[2]};
}

std::string YamlValue::asPath(const std::string& what) const {
  std::filesystem::path p = asString(what);
  if (p.is_relative()) p = std::filesystem::path(*impl_->file).parent_path() / p;
  return p.lexically_normal().string();
}

void YamlValue::fail(const std::string& message) const {
  throw InputError(*impl_->file, impl_->line, impl_->path.empty() ? "(document)" : impl_->path, message);
}

void YamlValue::failExpected(const std::string& what) const {
  fail("expected " + what + ", got " + describe(impl_->node));
}

void YamlValue::relocate(const InputError& error) const {
  if (error.located()) throw error;
  if (error.keyPath().empty()) fail(error.message());
  // The key path below this value; failing that, its shorter tails (a parameter of a symmetric set written
  // at the top level, e.g. "positive.alpha0" given as "alpha0").
  const std::vector<std::string> parts = splitKeyPath(error.keyPath());
  for (size_t first = 0; first < parts.size(); ++first) {
    YamlValue target = *this;
    bool found = true;
    for (size_t k = first; k < parts.size() && found; ++k) {
      const std::string& p = parts[k];
      if (p.front() == '[') {
        const size_t index = static_cast<size_t>(std::strtoul(p.c_str() + 1, nullptr, 10));
        found = target.isSequence() && index < target.size();
        if (found) target = target.at(index);
      } else {
        found = target.has(p);
        if (found) target = target[p];
      }
    }
    if (found) target.fail(error.message());
  }
  fail(error.keyPath() + ": " + error.message());
}

}  // namespace jointsim::io
