#include "jointsim/drive/drive_yaml.hpp"

#include <string>
#include <vector>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/friction_models.hpp"

namespace jointsim::drive {
namespace {

using io::YamlValue;

const std::vector<std::string> kTypes{"coulomb_viscous", "table", "stribeck", "dahl", "lugre", "lugre_ur5"};

// Optional number: the key's value, or the C++ default when absent.
double optional(const YamlValue& node, const char* key, double fallback, const std::string& what) {
  return node[key].asDouble(fallback, what);
}
double required(const YamlValue& node, const char* key, const std::string& what) {
  return node.required(key, what).asDouble(what);
}

StribeckBranch readBranch(const YamlValue& n) {
  StribeckBranch b;
  b.alpha0 = required(n, "alpha0", "Coulomb friction alpha0 in N·m");
  b.alpha1 = required(n, "alpha1", "additional stiction alpha1 in N·m");
  b.alpha2 = required(n, "alpha2", "viscous coefficient alpha2 in N·m·s/rad");
  b.v_s = required(n, "v_s", "Stribeck velocity v_s in rad/s");
  return b;
}

// Either symmetric alpha0/alpha1/alpha2/v_s at `node`, or positive/negative sub-mappings.
void readStaticSet(const YamlValue& node, StribeckBranch& positive, StribeckBranch& negative) {
  if (node.has("positive") || node.has("negative")) {
    for (const char* key : {"alpha0", "alpha1", "alpha2", "v_s"})
      if (node.has(key))
        node[key].fail("give the static parameters either for both directions (alpha0, alpha1, alpha2, v_s) or "
                       "per direction (positive: {...}, negative: {...}), not both");
    const std::string what = "mapping {alpha0 [N·m], alpha1 [N·m], alpha2 [N·m·s/rad], v_s [rad/s]}";
    for (const char* side : {"positive", "negative"}) {
      const YamlValue n = node.required(side, "static parameters for v " +
                                                  std::string(side[0] == 'p' ? ">= 0" : "< 0") + ", a " + what);
      n.expectMap("a " + what);
      n.allowKeys({"alpha0", "alpha1", "alpha2", "v_s"});
      (side[0] == 'p' ? positive : negative) = readBranch(n);
    }
  } else {
    if (!node.has("alpha0"))
      node.fail("missing static friction parameters: give alpha0 [N·m], alpha1 [N·m], alpha2 [N·m·s/rad], "
                "v_s [rad/s] (both directions) or positive: {...} and negative: {...} (per direction)");
    positive = negative = readBranch(node);
  }
}

std::unique_ptr<Friction> build(const YamlValue& node, const std::string& type) {
  if (type == "coulomb_viscous") {
    node.allowKeys({"type", "f_c", "f_v", "v_reg"});
    CoulombViscousParams p;
    p.f_c = required(node, "f_c", "Coulomb friction F_C in N·m");
    p.f_v = required(node, "f_v", "viscous coefficient F_v in N·m·s/rad");
    p.v_reg = optional(node, "v_reg", p.v_reg, "regularisation velocity v_reg in rad/s");
    return std::make_unique<CoulombViscousFriction>(p);
  }
  if (type == "table") {
    node.allowKeys({"type", "tau_pos", "peak", "v_stick", "d_stick"});
    TableFrictionParams p;
    const std::string row_what = "a table row [w in rad/s, tau in N·m]";
    const YamlValue t = node.required("tau_pos", "sliding friction table [[w in rad/s, tau in N·m], ...]");
    t.expectSequence("a sliding friction table [[w in rad/s, tau in N·m], ...]");
    p.tau_pos.clear();
    if (t.size() > 0 && !t.at(0).isSequence()) {  // single row written flat: [w, tau]
      const auto r = t.asDoubles(2, row_what);
      p.tau_pos.push_back({r[0], r[1]});
    } else {
      for (size_t i = 0; i < t.size(); ++i) {
        const auto r = t.at(i).asDoubles(2, row_what);
        p.tau_pos.push_back({r[0], r[1]});
      }
    }
    p.peak = optional(node, "peak", p.peak, "stiction factor peak (-), >= 1");
    p.v_stick = optional(node, "v_stick", p.v_stick, "sticking band half-width v_stick in rad/s");
    p.d_stick = optional(node, "d_stick", p.d_stick, "sticking damping d_stick in N·m·s/rad (0 = automatic)");
    return std::make_unique<TableFriction>(p);
  }
  if (type == "stribeck") {
    node.allowKeys({"type", "alpha0", "alpha1", "alpha2", "v_s", "positive", "negative", "delta", "k_s"});
    StribeckParams p;
    readStaticSet(node, p.positive, p.negative);
    p.delta = optional(node, "delta", p.delta, "Stribeck form factor delta (-)");
    p.k_s = optional(node, "k_s", p.k_s, "slope-limiter factor k_s in s/rad");
    return std::make_unique<StribeckFriction>(p);
  }
  if (type == "dahl") {
    node.allowKeys({"type", "sigma", "f_c", "alpha"});
    DahlParams p;
    p.sigma = required(node, "sigma", "rest stiffness sigma in N·m/rad");
    p.f_c = required(node, "f_c", "Coulomb friction F_C in N·m");
    p.alpha = optional(node, "alpha", p.alpha, "form factor alpha (-)");
    return std::make_unique<DahlFriction>(p);
  }
  if (type == "lugre") {
    node.allowKeys({"type", "sigma0", "sigma1", "alpha0", "alpha1", "alpha2", "v_s", "positive", "negative"});
    LuGreParams p;
    p.sigma0 = required(node, "sigma0", "bristle stiffness sigma0 in N·m/rad");
    p.sigma1 = required(node, "sigma1", "bristle damping sigma1 in N·m·s/rad");
    readStaticSet(node, p.positive, p.negative);
    return std::make_unique<LuGreFriction>(p);
  }
  // lugre_ur5
  node.allowKeys({"type", "sigma0", "sigma1", "qd_s", "k_static", "viscous_exponent", "f_c", "f_v", "k_q"});
  LuGreUr5Params p;
  p.f_c = required(node, "f_c", "Coulomb coefficient f_c in N·m (not given by [Raviola2023])");
  p.f_v = required(node, "f_v", "viscous coefficient f_v in N·m·(s/rad)^(2/3) (not given by [Raviola2023])");
  p.k_q = required(node, "k_q", "Stribeck shape factor k_q (-) (not given by [Raviola2023]; 1 is a sensible start)");
  p.sigma0 = optional(node, "sigma0", p.sigma0, "bristle stiffness sigma0 in N·m/rad");
  p.sigma1 = optional(node, "sigma1", p.sigma1, "bristle damping sigma1 in N·m·s/rad");
  p.qd_s = optional(node, "qd_s", p.qd_s, "sliding-speed threshold qd_s in rad/s");
  p.k_static = optional(node, "k_static", p.k_static, "static increment K_static (-)");
  p.viscous_exponent = optional(node, "viscous_exponent", p.viscous_exponent, "viscous exponent (-)");
  return std::make_unique<LuGreUr5Friction>(p);
}

}  // namespace

std::unique_ptr<Friction> frictionFromYaml(const io::YamlValue& node) {
  std::string list;
  for (const auto& t : kTypes) list += (list.empty() ? "" : ", ") + t;
  node.expectMap("a friction mapping {type: <" + list + ">, parameters...}");
  const YamlValue type_node = node.required("type", "friction model, one of " + list);
  const std::string type = type_node.asString("a friction type name (" + list + ")");
  bool known = false;
  for (const auto& t : kTypes) known = known || t == type;
  if (!known) {
    std::string msg = "unknown friction type '" + type + "'";
    if (const std::string near = io::closestMatch(type, kTypes); !near.empty())
      msg += " (did you mean '" + near + "'?)";
    type_node.fail(msg + "; expected one of " + list);
  }
  try {
    return build(node, type);
  } catch (const InputError& e) {
    node.relocate(e);  // validate() errors carry the key; the reader's own errors are located already
  }
}

}  // namespace jointsim::drive
