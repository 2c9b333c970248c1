#include "jointsim/common/check.hpp"

#include <cmath>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"

namespace jointsim::check {
namespace {
std::string withUnit(const std::string& rule, const std::string& unit) {
  return unit.empty() ? rule : rule + " " + unit;
}
}  // namespace

void fail(const std::string& component, const std::string& key, const std::string& rule, double value) {
  throw InputError::parameter(component, key, "expected " + rule + ", got " + formatNumber(value));
}

void fail(const std::string& component, const std::string& key, const std::string& rule) {
  throw InputError::parameter(component, key, rule);
}

void positive(const std::string& component, const std::string& key, double value, const std::string& unit) {
  if (!(value > 0.0) || !std::isfinite(value)) fail(component, key, withUnit("a finite value > 0", unit), value);
}

void nonNegative(const std::string& component, const std::string& key, double value, const std::string& unit) {
  if (!(value >= 0.0) || !std::isfinite(value)) fail(component, key, withUnit("a finite value >= 0", unit), value);
}

void finite(const std::string& component, const std::string& key, double value, const std::string& unit) {
  if (!std::isfinite(value)) fail(component, key, withUnit("a finite value", unit), value);
}

void atLeast(const std::string& component, const std::string& key, double value, double minimum,
             const std::string& unit) {
  if (!(value >= minimum) || !std::isfinite(value))
    fail(component, key, withUnit("a finite value >= " + formatNumber(minimum), unit), value);
}

void nonZero(const std::string& component, const std::string& key, double value, const std::string& unit) {
  if (!(value != 0.0) || !std::isfinite(value)) fail(component, key, withUnit("a finite non-zero value", unit), value);
}

void that(bool condition, const std::string& component, const std::string& key, const std::string& rule) {
  if (!condition) fail(component, key, rule);
}

}  // namespace jointsim::check
