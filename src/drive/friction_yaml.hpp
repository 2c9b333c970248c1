#pragma once
// Internal: builds a friction model from a YAML mapping {type: <name>, <parameters>}. Not part of the
// public API (yaml-cpp stays a private dependency).
//
// Keys per type (units in brackets; "req" = required; other keys take the C++ defaults of
// friction_models.hpp):
//   coulomb_viscous: f_c [N·m] req, f_v [N·m·s/rad] req, v_reg [rad/s]
//   table:           tau_pos [[w rad/s, tau N·m], ...] req (a single row may be written [w, tau]),
//                    peak [-], v_stick [rad/s], d_stick [N·m·s/rad] (0 = automatic)
//   stribeck:        static set, delta [-], k_s [s/rad]
//   dahl:            sigma [N·m/rad] req, f_c [N·m] req, alpha [-]
//   lugre:           sigma0 [N·m/rad] req, sigma1 [N·m·s/rad] req, static set
//   lugre_ur5:       f_c [N·m] req, f_v [N·m·(s/rad)^(2/3)] req, k_q [-] req, sigma0 [N·m/rad],
//                    sigma1 [N·m·s/rad], qd_s [rad/s], k_static [-], viscous_exponent [-]
// "static set" = either alpha0 [N·m], alpha1 [N·m], alpha2 [N·m·s/rad], v_s [rad/s] (all req, same
// for both directions), or the mappings positive: {alpha0, alpha1, alpha2, v_s} and negative: {...}
// (both req; per direction, 004 Table 4.3) — not both forms.
//
// Every error is an InputError "FILE:LINE: KEY.PATH: message", pointing at the offending key
// (parameter rules of validate() included).

#include <memory>

// Relative on purpose: the test targets do not have src/ on their include path (tests/CMakeLists.txt).
#include "../io/yaml_reader.hpp"
#include "jointsim/drive/friction.hpp"

namespace jointsim::drive {

/// Friction model described by `node` (a mapping with a `type` key).
/// \throws InputError with file:line: key.path on any missing, unknown or invalid key.
std::unique_ptr<Friction> frictionFromYaml(const io::YamlValue& node);

}  // namespace jointsim::drive
