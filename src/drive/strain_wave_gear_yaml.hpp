#pragma once
// Internal: strain-wave-gear parameters from YAML. Not part of the public API (yaml-cpp stays a private
// dependency).
//
// Keys (all optional except as noted; units in brackets, SI except alpha_t_deg):
//   type:          strain_wave_gear (optional; if present it must be this value)
//   size:          A | B — start from StrainWaveGearParams::ur5SizeA() / ur5SizeB() (002 Table 3).
//                  Without `size` every physical parameter below is required (except the damping
//                  values, which default to 0.1, and tau, which defaults to 101).
//   r_g [m], K_WG [N·m/rad], K_b [N/m], K_FS [N·m/rad], K_m [N/m], K_CS [N·m/rad],
//   J_WG [kg·m²], J_FS [kg·m²], J_CS [kg·m²]                       override single parameters
//   alpha_t_deg [deg] or alpha_t [rad] (not both)                  tooth pressure angle
//   tau [-] or Z_FS and Z_CS [teeth] (tau = Z_CS/(Z_CS − Z_FS))    reduction ratio (not both forms)
//   reaction_form: energy_consistent (default) | paper_literal
//   damping:       {mode: coefficient (default) | damping_ratio, value: <number>}
//                  `value` sets all five c_* (coefficients in N·m·s/rad or N·s/m, or damping ratios ζ
//                  [-] in damping_ratio mode); without `value` the preset numbers (0.1) are kept and
//                  read in the given mode.
//   c_WG, c_b, c_m, c_FS, c_CS                                     per-element damping, applied after
//                  damping.value (same units/meaning as in StrainWaveGearParams).
//
// Example:  {size: B, K_b: 1.5e8, reaction_form: paper_literal, damping: {mode: damping_ratio, value: 0.05}}
//
// Every error is an InputError "FILE:LINE: KEY.PATH: message" pointing at the offending key (unknown
// keys via allowKeys with a suggestion; parameter rules of StrainWaveGearParams::validate() included).

#include "io/yaml_reader.hpp"
#include "jointsim/drive/strain_wave_gear.hpp"

namespace jointsim::drive {

/// Parameters described by `node` (a mapping, see above). \throws InputError (file:line: key.path).
StrainWaveGearParams swgParamsFromYaml(const io::YamlValue& node);

}  // namespace jointsim::drive
