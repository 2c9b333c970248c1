// Tests of the drive components' parameter tables (include/jointsim/drive/parameters.hpp): every key of every
// component reads the value the component was built with, changes exactly that value (checked against a component
// built directly from its parameter struct, and by its effect on the component's equations), refuses unknown keys and
// values out of range, and the faults' roles select the parameters they did before the tables existed.

#include "jointsim/drive/parameters.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/dc_motor.hpp"
#include "jointsim/drive/friction_models.hpp"
#include "jointsim/drive/strain_wave_gear.hpp"
#include "jointsim/drive/transmissions.hpp"

namespace {

using namespace jointsim::drive;
using jointsim::InputError;

// The component's response at a fixed set of inputs: port torques, internal derivatives and the ratio.
std::vector<double> response(const Transmission& t) {
  std::vector<double> out{t.ratio(), static_cast<double>(t.stateSize())};
  if (t.isRigid()) return out;
  const int n = t.stateSize();
  for (const ShaftPorts p :
       {ShaftPorts{0.3, 2.0, 0.002, 0.01}, ShaftPorts{-0.01, -0.4, 0.0, 0.05}, ShaftPorts{1.0, 30.0, 0.0095, 0.3}}) {
    std::vector<double> x(static_cast<size_t>(n)), xdot(static_cast<size_t>(n));
    t.initialState(p.q_in, p.q_out, x.data());
    for (int i = 0; i < n; ++i) x[static_cast<size_t>(i)] += 1e-5 * (i + 1);  // off equilibrium: every element acts
    const PortTorques tau = t.evaluate(p, x.data(), xdot.data());
    out.push_back(tau.tau_in);
    out.push_back(tau.tau_out);
    out.push_back(t.storedEnergy(p, x.data()));
    out.insert(out.end(), xdot.begin(), xdot.end());
  }
  return out;
}

std::vector<double> response(const Friction& f) {
  std::vector<double> out{static_cast<double>(f.stateSize())};
  for (double v : {-1.0, -0.02, -1e-4, 0.0, 2e-4, 1.1e-3, 0.01, 0.5, 3.0})
    for (double drive : {0.0, 0.05, 0.3, 12.0})
      for (double z0 : {0.0, 2e-6, -3e-5}) {
        double z[1] = {z0}, zdot[1] = {0.0};
        out.push_back(f.evaluate({v, drive}, z, zdot));
        out.push_back(zdot[0]);
      }
  for (double v : {-2.0, -0.03, 0.03, 0.1, 2.0}) out.push_back(f.steadyState(v));
  return out;
}

// A changed value inside the range: ×1.3 (or +0.3 from 0), or half-way to an upper bound.
double changedValue(const ParameterInfo& p) {
  double v = p.value == 0.0 ? 0.3 : p.value * 1.3;
  if (std::isfinite(p.range.max) && !p.range.contains(v)) v = 0.5 * (p.value + p.range.max);
  return v;
}

// Every key: the table reads it back, a change appears in the new table under that key only and changes the
// component's equations; all keys at their values give the same component. `rebuilt` checks a key against the
// component built from its parameter struct (independent of the table's key → field map).
template <class C, class Base>
void checkTable(const C& c, const std::function<std::shared_ptr<const Base>(const std::string&, double)>& rebuilt) {
  const std::vector<ParameterInfo> table = c.parameters();
  ASSERT_FALSE(table.empty()) << c.type();
  ParameterChanges all;
  for (const auto& p : table) all.push_back({p.key, p.value});
  EXPECT_EQ(response(*c.withParameters(all)), response(c)) << c.type();
  for (const auto& p : table) {
    SCOPED_TRACE(c.type() + " " + p.key);
    EXPECT_TRUE(p.range.contains(p.value)) << p.value << " " << p.range.text();
    EXPECT_FALSE(p.unit.empty());
    EXPECT_FALSE(p.description.empty());
    const double v = changedValue(p);
    const auto changed = c.withParameters({{p.key, v}});
    const auto t2 = changed->parameters();
    ASSERT_EQ(t2.size(), table.size());
    for (size_t i = 0; i < table.size(); ++i)
      EXPECT_EQ(t2[i].value, t2[i].key == p.key ? v : table[i].value) << t2[i].key;
    EXPECT_NE(response(*changed), response(c)) << "the parameter has no effect";
    if (auto direct = rebuilt(p.key, v)) {
      EXPECT_EQ(response(*changed), response(*direct));
      EXPECT_EQ(changed->type(), direct->type());
    }
  }
}

TEST(ParameterTables, EveryTransmissionKeyReadsChangesAndActsOnItsOwnField) {
  ElasticGearParams e;
  e.ratio = 101;
  e.stiffness = 3e3;
  e.damping = 0.4;
  checkTable<ElasticGear, Transmission>(ElasticGear(e), [&](const std::string& key, double v) {
    auto p = e;
    if (key == "ratio") p.ratio = v;
    if (key == "stiffness") p.stiffness = v;
    if (key == "damping") p.damping = v;
    if (key == "backlash") {
      ElastoBacklashParams q;
      q.ratio = p.ratio;
      q.stiffness = p.stiffness;
      q.damping = p.damping;
      q.backlash = v;
      return std::shared_ptr<const Transmission>(std::make_shared<ElastoBacklash>(q));
    }
    return std::shared_ptr<const Transmission>(std::make_shared<ElasticGear>(p));
  });
  ElastoBacklashParams b;
  b.ratio = 50;
  b.stiffness = 2e3;
  b.damping = 0.2;
  b.backlash = 0.02;
  b.side = ComplianceSide::Output;
  checkTable<ElastoBacklash, Transmission>(ElastoBacklash(b), [&](const std::string& key, double v) {
    auto p = b;
    if (key == "backlash")
      p.backlash = v;
    else if (key == "stiffness")
      p.stiffness = v;
    else
      return std::shared_ptr<const Transmission>();
    return std::shared_ptr<const Transmission>(std::make_shared<ElastoBacklash>(p));
  });
  checkTable<RigidGear, Transmission>(RigidGear(7.0), [](const std::string&, double v) {
    return std::shared_ptr<const Transmission>(std::make_shared<RigidGear>(v));
  });
  for (const auto mode : {DampingMode::Coefficient, DampingMode::DampingRatio}) {
    auto s = StrainWaveGearParams::ur5SizeB();
    s.damping_mode = mode;
    checkTable<StrainWaveGear, Transmission>(StrainWaveGear(s), [&](const std::string& key, double v) {
      auto p = s;
      if (key == "K_m")
        p.K_m = v;
      else if (key == "alpha_t")
        p.alpha_t = v;
      else if (key == "c_FS")
        p.c_FS = v;
      else
        return std::shared_ptr<const Transmission>();
      return std::shared_ptr<const Transmission>(std::make_shared<StrainWaveGear>(p));
    });
  }
}

TEST(ParameterTables, EveryFrictionKeyReadsChangesAndActsOnItsOwnField) {
  using Make = std::function<std::shared_ptr<const Friction>(const std::string&, double)>;
  const Make none = [](const std::string&, double) { return std::shared_ptr<const Friction>(); };
  CoulombViscousParams cv;
  checkTable<CoulombViscousFriction, Friction>(CoulombViscousFriction(cv), [&](const std::string& key, double v) {
    auto p = cv;
    if (key != "f_v") return std::shared_ptr<const Friction>();
    p.f_v = v;
    return std::shared_ptr<const Friction>(std::make_shared<CoulombViscousFriction>(p));
  });
  TableFrictionParams tp;
  tp.tau_pos = {{{0.0, 0.2}}, {{0.5, 0.3}}, {{2.0, 0.6}}};
  tp.peak = 1.4;
  tp.d_stick = 50.0;
  checkTable<TableFriction, Friction>(TableFriction(tp), [&](const std::string& key, double v) {
    auto p = tp;
    if (key != "tau_pos[1][1]") return std::shared_ptr<const Friction>();
    p.tau_pos[1][1] = v;
    return std::shared_ptr<const Friction>(std::make_shared<TableFriction>(p));
  });
  StribeckParams sp;
  checkTable<StribeckFriction, Friction>(StribeckFriction(sp), [&](const std::string& key, double v) {
    auto p = sp;
    if (key != "negative.alpha0") return std::shared_ptr<const Friction>();
    p.negative.alpha0 = v;
    return std::shared_ptr<const Friction>(std::make_shared<StribeckFriction>(p));
  });
  DahlParams dp;
  dp.alpha = 1.5;
  checkTable<DahlFriction, Friction>(DahlFriction(dp), none);
  LuGreParams lp;
  checkTable<LuGreFriction, Friction>(LuGreFriction(lp), [&](const std::string& key, double v) {
    auto p = lp;
    if (key != "positive.v_s") return std::shared_ptr<const Friction>();
    p.positive.v_s = v;
    return std::shared_ptr<const Friction>(std::make_shared<LuGreFriction>(p));
  });
  LuGreUr5Params up;
  up.f_c = 5.0;
  up.f_v = 2.0;
  up.k_q = 1.0;
  up.sigma0 = 2e3;  // slow enough bristles that z of the response grid is not saturated at once
  checkTable<LuGreUr5Friction, Friction>(LuGreUr5Friction(up), none);
}

TEST(ParameterTables, UnknownKeysAndValuesOutOfRangeAreRefusedNamingKeyUnitAndRange) {
  const ElasticGear gear(ElasticGearParams{});
  try {
    (void)gear.withParameters({{"stifness", 1.0}});
    FAIL() << "an unknown key was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'stifness'"), std::string::npos) << m;
    EXPECT_NE(m.find("stiffness, damping"), std::string::npos) << m;  // the known keys
  }
  try {
    (void)gear.withParameters({{"stiffness", -2.0}});
    FAIL() << "a negative stiffness was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("stiffness"), std::string::npos) << m;
    EXPECT_NE(m.find("(0, inf)"), std::string::npos) << m;
    EXPECT_NE(m.find("N·m/rad"), std::string::npos) << m;
  }
  EXPECT_THROW((void)gear.withParameters({{"damping", std::nan("")}}), InputError);
  // A rule coupling two rows is the component's own check: the speeds must increase.
  TableFrictionParams tp;
  tp.tau_pos = {{{0.0, 0.2}}, {{0.5, 0.3}}};
  EXPECT_THROW((void)TableFriction(tp).withParameters({{"tau_pos[1][0]", 0.0}}), InputError);
  EXPECT_THROW((void)TableFriction(tp).withParameters({{"tau_pos[2][0]", 1.0}}), InputError);  // no third row
  // The motor: a table of free functions on the parameter struct.
  DcMotorParams m = DcMotorParams::ur5(2);
  const auto changed = withParameters(m, {{"kt", 0.2}, {"R", 0.5}});
  EXPECT_EQ(changed.kt, 0.2);
  EXPECT_EQ(changed.R, 0.5);
  EXPECT_EQ(changed.ke, m.ke);
  EXPECT_THROW((void)withParameters(m, {{"L", 0.0}}), InputError);
  EXPECT_EQ(parameterValue(parameterTable(m), "J_M", "motor"), m.J_M);
  EXPECT_THROW((void)parameterValue(parameterTable(m), "J", "motor"), InputError);
}

TEST(ParameterTables, RolesSelectTheParametersTheFaultsActOn) {
  auto keys = [](const std::vector<ParameterInfo>& t, ParameterRole r) {
    std::vector<std::string> out;
    for (const auto& c : roleChanges(t, r, 2.0, false)) out.push_back(c.key);
    return out;
  };
  using V = std::vector<std::string>;
  EXPECT_EQ(keys(StrainWaveGear(StrainWaveGearParams{}).parameters(), ParameterRole::Stiffness),
            (V{"K_WG", "K_b", "K_FS", "K_m", "K_CS"}));
  EXPECT_EQ(keys(ElasticGear(ElasticGearParams{}).parameters(), ParameterRole::Stiffness), V{"stiffness"});
  EXPECT_EQ(keys(ElasticGear(ElasticGearParams{}).parameters(), ParameterRole::Backlash), V{"backlash"});
  EXPECT_TRUE(keys(RigidGear(3.0).parameters(), ParameterRole::Stiffness).empty());
  EXPECT_TRUE(keys(StrainWaveGear(StrainWaveGearParams{}).parameters(), ParameterRole::Backlash).empty());
  EXPECT_EQ(keys(LuGreFriction(LuGreParams{}).parameters(), ParameterRole::Coulomb),
            (V{"positive.alpha0", "negative.alpha0"}));
  EXPECT_EQ(keys(LuGreFriction(LuGreParams{}).parameters(), ParameterRole::BristleStiffness), V{"sigma0"});
  EXPECT_EQ(keys(DahlFriction(DahlParams{}).parameters(), ParameterRole::BristleStiffness), V{"sigma"});
  EXPECT_TRUE(keys(StribeckFriction(StribeckParams{}).parameters(), ParameterRole::BristleStiffness).empty());
  EXPECT_EQ(keys(TableFriction(TableFrictionParams{}).parameters(), ParameterRole::Coulomb),
            (V{"tau_pos[0][1]", "tau_pos[1][1]"}));
  EXPECT_EQ(keys(parameterTable(DcMotorParams{}), ParameterRole::TorqueConstant), (V{"kt", "ke"}));
  // Scale and offset.
  const auto table = ElastoBacklash(ElastoBacklashParams{1.0, 4.0, 0.0, 0.01}).parameters();
  const auto scaled = roleChanges(table, ParameterRole::Stiffness, 0.5, false);
  ASSERT_EQ(scaled.size(), 1u);
  EXPECT_EQ(scaled[0].value, 2.0);
  const auto added = roleChanges(table, ParameterRole::Backlash, 0.02, true);
  ASSERT_EQ(added.size(), 1u);
  EXPECT_EQ(added[0].value, 0.01 + 0.02);
}

TEST(ParameterTables, RangesAndTheirText) {
  EXPECT_EQ(ParameterRange::positive().text(), "(0, inf)");
  EXPECT_EQ(ParameterRange::nonNegative().text(), "[0, inf)");
  EXPECT_FALSE(ParameterRange::positive().contains(0.0));
  EXPECT_TRUE(ParameterRange::nonNegative().contains(0.0));
  EXPECT_FALSE(ParameterRange::nonNegative().contains(INFINITY));
  const ParameterRange r{0.0, 1.0, true, true};
  EXPECT_FALSE(r.contains(1.0));
  EXPECT_TRUE(r.contains(0.5));
  EXPECT_EQ(r.text(), "(0, 1)");
  EXPECT_STREQ(roleName(ParameterRole::BristleStiffness), "bristle_stiffness");
}

}  // namespace
