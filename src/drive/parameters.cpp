#include "jointsim/drive/parameters.hpp"

#include <cmath>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/drive/friction.hpp"
#include "jointsim/drive/transmission.hpp"

namespace jointsim::drive {
namespace {
std::string knownKeys(const std::vector<std::string>& keys) {
  std::string s;
  for (const auto& k : keys) s += (s.empty() ? "" : ", ") + k;
  return s.empty() ? "none" : s;
}
}  // namespace

const char* roleName(ParameterRole role) {
  switch (role) {
    case ParameterRole::None: return "none";
    case ParameterRole::Stiffness: return "stiffness";
    case ParameterRole::Backlash: return "backlash";
    case ParameterRole::Coulomb: return "coulomb";
    case ParameterRole::BristleStiffness: return "bristle_stiffness";
    case ParameterRole::TorqueConstant: return "torque_constant";
  }
  return "none";
}

bool ParameterRange::contains(double v) const {
  if (!std::isfinite(v)) return false;
  if (min_open ? !(v > min) : !(v >= min)) return false;
  if (max_open ? !(v < max) : !(v <= max)) return false;
  return true;
}

std::string ParameterRange::text() const {
  auto bound = [](double b) { return std::isinf(b) ? std::string(b < 0 ? "-inf" : "inf") : formatNumber(b); };
  return std::string(min_open || std::isinf(min) ? "(" : "[") + bound(min) + ", " + bound(max) +
         (max_open || std::isinf(max) ? ")" : "]");
}

std::vector<ParameterInfo> describeParameters(const std::vector<ParameterRef>& refs) {
  std::vector<ParameterInfo> out;
  out.reserve(refs.size());
  for (const ParameterRef& r : refs) {
    out.push_back(r.info);
    out.back().value = *r.target;
  }
  return out;
}

void assignParameters(const std::vector<ParameterRef>& refs, const ParameterChanges& changes,
                      const std::string& component) {
  for (const ParameterChange& c : changes) {
    const ParameterRef* found = nullptr;
    for (const ParameterRef& r : refs)
      if (r.info.key == c.key) found = &r;
    if (found == nullptr) {
      std::vector<std::string> keys;
      for (const ParameterRef& r : refs) keys.push_back(r.info.key);
      throw InputError(component + ": no parameter '" + c.key + "' (it has " + knownKeys(keys) + ")");
    }
    if (!found->info.range.contains(c.value))
      check::fail(component, c.key, "a value in " + found->info.range.text() + " " + found->info.unit, c.value);
    *found->target = c.value;
  }
}

ParameterChanges roleChanges(const std::vector<ParameterInfo>& table, ParameterRole role, double amount, bool add) {
  ParameterChanges out;
  for (const ParameterInfo& p : table)
    if (p.role == role) out.push_back({p.key, add ? p.value + amount : p.value * amount});
  return out;
}

bool hasRole(const std::vector<ParameterInfo>& table, ParameterRole role) {
  for (const ParameterInfo& p : table)
    if (p.role == role) return true;
  return false;
}

double parameterValue(const std::vector<ParameterInfo>& table, const std::string& key, const std::string& component) {
  std::vector<std::string> keys;
  for (const ParameterInfo& p : table) {
    if (p.key == key) return p.value;
    keys.push_back(p.key);
  }
  throw InputError(component + ": no parameter '" + key + "' (it has " + knownKeys(keys) + ")");
}

}  // namespace jointsim::drive

namespace jointsim::drive {
namespace {
[[noreturn]] void noTable(const std::string& component, const ParameterChanges& changes) {
  throw InputError(component + ": no parameter '" + (changes.empty() ? std::string() : changes.front().key) +
                   "' (the component has no parameter table)");
}
}  // namespace

std::shared_ptr<const Transmission> Transmission::withParameters(const ParameterChanges& changes) const {
  noTable(type() + " transmission", changes);
}

std::shared_ptr<const Friction> Friction::withParameters(const ParameterChanges& changes) const {
  noTable(type() + " friction", changes);
}

}  // namespace jointsim::drive
