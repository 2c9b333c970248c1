#include "jointsim/drive/drive_yaml.hpp"

#include <cmath>
#include <sstream>
#include <string>

#include "common/constants.hpp"
#include "jointsim/common/error.hpp"

namespace jointsim::drive {
namespace {

using io::YamlValue;

struct Field {
  const char* key;
  double StrainWaveGearParams::*member;
  const char* what;
};

// Physical parameters that are required when no `size` preset is given.
const Field kPhysical[] = {
    {"r_g", &StrainWaveGearParams::r_g, "primitive radius r_g in m"},
    {"K_WG", &StrainWaveGearParams::K_WG, "motor shaft-WG stiffness K_WG in N·m/rad"},
    {"K_b", &StrainWaveGearParams::K_b, "WG bearing radial stiffness K_b in N/m"},
    {"K_FS", &StrainWaveGearParams::K_FS, "flexspline torsional stiffness K_FS in N·m/rad"},
    {"K_m", &StrainWaveGearParams::K_m, "mesh stiffness K_m in N/m"},
    {"K_CS", &StrainWaveGearParams::K_CS, "CS-output stiffness K_CS in N·m/rad"},
    {"J_WG", &StrainWaveGearParams::J_WG, "wave generator inertia J_WG in kg·m²"},
    {"J_FS", &StrainWaveGearParams::J_FS, "flexspline inertia J_FS in kg·m²"},
    {"J_CS", &StrainWaveGearParams::J_CS, "circular spline inertia J_CS in kg·m²"},
};

const Field kDamping[] = {
    {"c_WG", &StrainWaveGearParams::c_WG, "damping c_WG (N·m·s/rad, or a damping ratio)"},
    {"c_b", &StrainWaveGearParams::c_b, "damping c_b (N·s/m, or a damping ratio)"},
    {"c_m", &StrainWaveGearParams::c_m, "damping c_m (N·s/m, or a damping ratio)"},
    {"c_FS", &StrainWaveGearParams::c_FS, "damping c_FS (N·m·s/rad, or a damping ratio)"},
    {"c_CS", &StrainWaveGearParams::c_CS, "damping c_CS (N·m·s/rad, or a damping ratio)"},
};

// Re-throws an error of StrainWaveGearParams::validate() at the YAML key that set its field: the field's own
// key, or the key it was derived from (alpha_t from alpha_t_deg, tau from Z_CS, c_* from damping.value).
[[noreturn]] void rethrowAtKey(const YamlValue& node, const InputError& e) {
  const std::string& field = e.keyPath();
  if (!node.has(field)) {
    if (field == "alpha_t" && node.has("alpha_t_deg")) node["alpha_t_deg"].fail(e.message());
    if (field == "tau" && node.has("Z_CS")) node["Z_CS"].fail(e.message());
    if (field.rfind("c_", 0) == 0 && node["damping"].has("value")) node["damping"]["value"].fail(e.message());
  }
  node.relocate(e);
}

}  // namespace

StrainWaveGearParams swgParamsFromYaml(const YamlValue& node) {
  node.expectMap("a strain wave gear mapping, e.g. {size: A}");
  node.allowKeys({"type", "size", "r_g",  "alpha_t", "alpha_t_deg", "tau",           "Z_FS",   "Z_CS",
                  "K_WG", "K_b",  "K_FS", "K_m",     "K_CS",        "J_WG",          "J_FS",   "J_CS",
                  "c_WG", "c_b",  "c_m",  "c_FS",    "c_CS",        "reaction_form", "damping"});
  if (node.has("type")) {
    const std::string type = node["type"].asString("the transmission type 'strain_wave_gear'");
    if (type != "strain_wave_gear") node["type"].fail("expected 'strain_wave_gear', got '" + type + "'");
  }

  StrainWaveGearParams p;
  const bool preset = node.has("size");
  if (preset) {
    const std::string size = node["size"].asString("a gear size A or B");
    if (size == "A" || size == "a")
      p = StrainWaveGearParams::ur5SizeA();
    else if (size == "B" || size == "b")
      p = StrainWaveGearParams::ur5SizeB();
    else
      node["size"].fail("expected A (UR5 joints 1-3) or B (UR5 joints 4-6) of [Raviola2023, Table 3], got '" + size +
                        "'");
  }

  for (const Field& f : kPhysical) {
    if (preset)
      p.*f.member = node[f.key].asDouble(p.*f.member, f.what);
    else
      p.*f.member = node.required(f.key, f.what + std::string(" (no 'size' preset given)")).asDouble(f.what);
  }

  // Pressure angle: alpha_t [rad] or alpha_t_deg [deg].
  if (node.has("alpha_t") && node.has("alpha_t_deg"))
    node["alpha_t_deg"].fail("give either alpha_t [rad] or alpha_t_deg [deg], not both");
  if (node.has("alpha_t")) {
    p.alpha_t = node["alpha_t"].asDouble("pressure angle alpha_t in rad");
  } else if (node.has("alpha_t_deg")) {
    const double deg = node["alpha_t_deg"].asDouble("pressure angle alpha_t_deg in degrees");
    if (!(deg > 0.0 && deg < 90.0)) {
      std::ostringstream os;
      os << "expected a pressure angle in (0, 90) deg, got " << deg;
      node["alpha_t_deg"].fail(os.str());
    }
    p.alpha_t = deg * kPi / 180.0;
  } else if (!preset) {
    node.required("alpha_t_deg", "pressure angle alpha_t_deg in degrees, or alpha_t in rad (no 'size' preset given)");
  }

  // Reduction ratio: tau, or the tooth numbers.
  const bool teeth = node.has("Z_FS") || node.has("Z_CS");
  if (teeth) {
    if (node.has("tau")) node["tau"].fail("give either tau or the tooth numbers Z_FS and Z_CS, not both");
    const long z_fs = node.required("Z_FS", "flexspline tooth number (with Z_CS)").asInt("a tooth number");
    const long z_cs = node.required("Z_CS", "circular spline tooth number (with Z_FS)").asInt("a tooth number");
    if (z_fs <= 0) node["Z_FS"].fail("expected a tooth number > 0, got " + std::to_string(z_fs));
    if (z_cs <= z_fs)
      node["Z_CS"].fail("expected more teeth than the flexspline (Z_FS = " + std::to_string(z_fs) + "), got " +
                        std::to_string(z_cs));
    p.tau = static_cast<double>(z_cs) / static_cast<double>(z_cs - z_fs);  // eq. 2
  } else {
    p.tau = node["tau"].asDouble(p.tau, "reduction ratio tau");
  }

  if (node.has("reaction_form")) {
    const std::string form = node["reaction_form"].asString("energy_consistent or paper_literal");
    if (form == "energy_consistent")
      p.reaction_form = ReactionForm::EnergyConsistent;
    else if (form == "paper_literal")
      p.reaction_form = ReactionForm::PaperLiteral;
    else
      node["reaction_form"].fail("expected energy_consistent (tan(alpha_n), ratio exactly tau) or paper_literal "
                                 "(sin(alpha_n)cos(alpha_n) as printed in [Raviola2023]), got '" +
                                 form + "'");
  }

  if (node.has("damping")) {
    const YamlValue d = node["damping"];
    d.expectMap("a mapping {mode: coefficient|damping_ratio, value: <number>}");
    d.allowKeys({"mode", "value"});
    if (d.has("mode")) {
      const std::string mode = d["mode"].asString("coefficient or damping_ratio");
      if (mode == "coefficient")
        p.damping_mode = DampingMode::Coefficient;
      else if (mode == "damping_ratio")
        p.damping_mode = DampingMode::DampingRatio;
      else
        d["mode"].fail("expected coefficient (N·m·s/rad or N·s/m) or damping_ratio (zeta per element), got '" + mode +
                       "'");
    }
    if (d.has("value")) {
      const double v = d["value"].asDouble("a damping value (coefficient or damping ratio)");
      for (const Field& f : kDamping) p.*f.member = v;
    }
  }
  for (const Field& f : kDamping) p.*f.member = node[f.key].asDouble(p.*f.member, f.what);

  try {
    p.validate();
  } catch (const InputError& e) {
    rethrowAtKey(node, e);
  }
  return p;
}

}  // namespace jointsim::drive
