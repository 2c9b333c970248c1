#pragma once
/// \file
/// Parameter validation with one message format. Every check throws an InputError (InputError::parameter)
/// reading "COMPONENT: KEY: expected RULE [UNIT], got VALUE", whose key path is the parameter's key relative to
/// its component's YAML mapping (e.g. "positive.alpha0", "tau_pos[2]"); a YAML reader that catches it
/// re-throws it at that key's file and line as "FILE:LINE: FULL.KEY.PATH: expected RULE [UNIT], got VALUE"
/// (io::YamlValue::relocate).
///
///   check::positive("lugre", "sigma0", p.sigma0, "N·m/rad");   // finite and > 0
///   check::that("clamping axis 'j1'", "tau_pos", ok, "speeds increasing from 0 rad/s", ...);

#include <string>

namespace jointsim::check {

/// Throws "COMPONENT: KEY: expected RULE, got VALUE".
[[noreturn]] void fail(const std::string& component, const std::string& key, const std::string& rule, double value);
/// Throws "COMPONENT: KEY: RULE" (for rules that are not about one number).
[[noreturn]] void fail(const std::string& component, const std::string& key, const std::string& rule);

/// `value` finite and > 0.
void positive(const std::string& component, const std::string& key, double value, const std::string& unit);
/// `value` finite and >= 0.
void nonNegative(const std::string& component, const std::string& key, double value, const std::string& unit);
/// `value` finite.
void finite(const std::string& component, const std::string& key, double value, const std::string& unit);
/// `value` finite and >= `minimum`.
void atLeast(const std::string& component, const std::string& key, double value, double minimum,
             const std::string& unit);
/// `value` finite and != 0.
void nonZero(const std::string& component, const std::string& key, double value, const std::string& unit);
/// `condition`, else fail(component, key, rule).
void that(bool condition, const std::string& component, const std::string& key, const std::string& rule);

}  // namespace jointsim::check
