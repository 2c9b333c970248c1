#pragma once
/// \file
/// Drive components from YAML: the blocks `motor`, `transmission` and `friction` of joint-rig experiments and
/// of robot-with-drives files. Every error is an InputError "FILE:LINE: KEY.PATH: message" pointing at the
/// offending key (parameter rules of the components' validate() included, relocated to their keys).

#include <memory>

#include "jointsim/drive/dc_motor.hpp"
#include "jointsim/drive/friction.hpp"
#include "jointsim/drive/strain_wave_gear.hpp"
#include "jointsim/drive/transmission.hpp"
#include "jointsim/io/yaml.hpp"

namespace jointsim::drive {

/// `motor: {preset: ur5_joint1..6, R [Ω], L [H], kt [N·m/A], ke [V·s/rad], J_M [kg·m²], V_supply [V]}` (preset
/// values overridable; without a preset R, L and kt are required; ke defaults to kt).
DcMotorParams motorFromYaml(const io::YamlValue& node);

/// `transmission: {type: rigid|elastic|elasto_backlash|strain_wave_gear, ...}`:
///   rigid:            ratio [-] (q_in/q_out, default 1)
///   elastic:          ratio, stiffness [N·m/rad] req, damping [N·m·s/rad], side: motor|output
///   elasto_backlash:  as elastic, plus backlash [rad] req (total)
///   strain_wave_gear: see swgParamsFromYaml
std::shared_ptr<const Transmission> transmissionFromYaml(const io::YamlValue& node);

/// Friction model described by `node` (a mapping with a `type` key).
///
/// Keys per type (units in brackets; "req" = required; other keys take the C++ defaults of
/// friction_models.hpp):
///   coulomb_viscous: f_c [N·m] req, f_v [N·m·s/rad] req, v_reg [rad/s]
///   table:           tau_pos [[w rad/s, tau N·m], ...] req (a single row may be written [w, tau]),
///                    peak [-], v_stick [rad/s], d_stick [N·m·s/rad] (0 = automatic)
///   stribeck:        static set, delta [-], k_s [s/rad]
///   dahl:            sigma [N·m/rad] req, f_c [N·m] req, alpha [-]
///   lugre:           sigma0 [N·m/rad] req, sigma1 [N·m·s/rad] req, static set
///   lugre_ur5:       f_c [N·m] req, f_v [N·m·(s/rad)^(2/3)] req, k_q [-] req, sigma0 [N·m/rad],
///                    sigma1 [N·m·s/rad], qd_s [rad/s], k_static [-], viscous_exponent [-]
/// "static set" = either alpha0 [N·m], alpha1 [N·m], alpha2 [N·m·s/rad], v_s [rad/s] (all req, same
/// for both directions), or the mappings positive: {alpha0, alpha1, alpha2, v_s} and negative: {...}
/// (both req; per direction, [Hauschild2003, Table 4.3]) — not both forms.
///
/// Every error is an InputError "FILE:LINE: KEY.PATH: message", pointing at the offending key
/// (parameter rules of validate() included).
std::unique_ptr<Friction> frictionFromYaml(const io::YamlValue& node);

/// Strain-wave-gear parameters described by `node` (a mapping).
///
/// Keys (all optional except as noted; units in brackets, SI except alpha_t_deg):
///   type:          strain_wave_gear (optional; if present it must be this value)
///   size:          A | B — start from StrainWaveGearParams::ur5SizeA() / ur5SizeB() ([Raviola2023, Table 3]).
///                  Without `size` every physical parameter below is required (except the damping
///                  values, which default to 0.1, and tau, which defaults to 101).
///   r_g [m], K_WG [N·m/rad], K_b [N/m], K_FS [N·m/rad], K_m [N/m], K_CS [N·m/rad],
///   J_WG [kg·m²], J_FS [kg·m²], J_CS [kg·m²]                       override single parameters
///   alpha_t_deg [deg] or alpha_t [rad] (not both)                  tooth pressure angle
///   tau [-] or Z_FS and Z_CS [teeth] (tau = Z_CS/(Z_CS − Z_FS))    reduction ratio (not both forms)
///   reaction_form: energy_consistent (default) | paper_literal
///   damping:       {mode: coefficient (default) | damping_ratio, value: <number>}
///                  `value` sets all five c_* (coefficients in N·m·s/rad or N·s/m, or damping ratios ζ
///                  [-] in damping_ratio mode); without `value` the preset numbers (0.1) are kept and
///                  read in the given mode.
///   c_WG, c_b, c_m, c_FS, c_CS                                     per-element damping, applied after
///                  damping.value (same units/meaning as in StrainWaveGearParams).
///
/// Example:  {size: B, K_b: 1.5e8, reaction_form: paper_literal, damping: {mode: damping_ratio, value: 0.05}}
///
/// Every error is an InputError "FILE:LINE: KEY.PATH: message" pointing at the offending key (unknown
/// keys via allowKeys with a suggestion; parameter rules of StrainWaveGearParams::validate() included).
StrainWaveGearParams swgParamsFromYaml(const io::YamlValue& node);

}  // namespace jointsim::drive
