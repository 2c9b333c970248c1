// The FMI 2.0 Co-Simulation instance (fmi::Instance, the C++ side of the FMU binary) without an importer: its
// results against the stepping simulator over the same experiment, parameters against --set, and the error
// paths of the state machine. The FMU archive itself is tested with FMPy (tests/python/test_fmu.py).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/fmi/fmu.hpp"
#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace jointsim;

namespace {

const std::string kRig = std::string(JOINTSIM_SOURCE_DIR) + "/config/experiments/ur5_swg_joint_velocity.yaml";
const std::string kUr5 = std::string(JOINTSIM_SOURCE_DIR) + "/config/experiments/ur5_excitation.yaml";

/// A resources folder with the description only; its experiment_file is the experiment in the source tree by a
/// relative path through ../ (the instance reads resources/<experiment_file>), so its own references resolve.
/// The folder is the test's own (test::TempDir).
struct Resources {
  test::TempDir tmp;
  fs::path dir;
  fmi::FmuDescription d;
  Resources(const std::string& config, const fmi::ExportOptions& o, const std::string& tag)
      : tmp(tag), dir(tmp.path()) {
    auto e = experiments::loadExperiment(config, o.overrides);
    d = fmi::describe(*e, o, "m");
    d.overrides = o.overrides;
    d.guid = "{test-" + tag + "}";
    d.experiment_file = fs::relative(fs::path(config), dir).string();
    std::ofstream(dir / "jointsim_fmu.json") << d.toJson().dump(1);
  }
};

unsigned vrOf(const fmi::FmuDescription& d, const std::string& name) {
  for (size_t i = 0; i < d.variables.size(); ++i)
    if (d.variables[i].name == name) return static_cast<unsigned>(i);
  ADD_FAILURE() << "no variable " << name;
  return 0;
}

struct Log {
  std::vector<std::string> lines;
  fmi::Logger logger() {
    return [this](fmi::Status, const char*, const std::string& m) { lines.push_back(m); };
  }
  bool mentions(const std::string& text) const {
    for (const auto& l : lines)
      if (l.find(text) != std::string::npos) return true;
    return false;
  }
};

}  // namespace

// The joint rig's experiment file has no relative references; the instance steps it exactly as the stepping
// simulator does (the same algorithm: values equal to rounding), with a parameter set through setReal acting
// as the same --set.
TEST(FmuInstance, MatchesSimulatorAndParameterActsAsSet) {
  fmi::ExportOptions o;
  Resources r(kRig, o, "rig");
  const unsigned vr_ki = vrOf(r.d, "input.controller.ki");
  const unsigned vr_v = vrOf(r.d, "output_velocity");
  double v_nominal = 0.0;
  for (double ki : {20.0, 5.0}) {  // 20: the file's value (start), 5: changed
    Log log;
    fmi::Instance inst("rig", r.dir.string(), r.d.guid, log.logger());
    ASSERT_EQ(inst.setupExperiment(false, 0, 0.0, false, 0), fmi::Status::OK);
    ASSERT_EQ(inst.setReal(&vr_ki, 1, &ki), fmi::Status::OK);
    ASSERT_EQ(inst.enterInitializationMode(), fmi::Status::OK);
    ASSERT_EQ(inst.exitInitializationMode(), fmi::Status::OK);
    auto sim = experiments::makeSimulator(std::shared_ptr<experiments::Experiment>(experiments::loadExperiment(
        kRig, ki == 20.0 ? std::vector<std::string>{} : std::vector<std::string>{"input.controller.ki=5"})));
    const int iv = sim->signalIndex("output_velocity");
    double t = 0.0, max_dev = 0.0, v_end = 0.0;
    for (int k = 0; k < 1500; ++k) {
      ASSERT_EQ(inst.doStep(t, 1e-3), fmi::Status::OK) << (log.lines.empty() ? "" : log.lines.back());
      t = sim->advance(1e-3);
      double v = 0.0;
      ASSERT_EQ(inst.getReal(&vr_v, 1, &v), fmi::Status::OK);
      max_dev = std::max(max_dev, std::abs(v - sim->signals()[iv]));
      v_end = v;
    }
    EXPECT_LE(max_dev, 1e-12) << "ki " << ki;
    EXPECT_NEAR(inst.time(), 1.5, 1e-12);
    if (ki == 20.0) {
      v_nominal = v_end;
      EXPECT_GT(v_nominal, 0.5);  // the profile ramps the joint to 1 rad/s over 1 s
    } else {
      EXPECT_GT(std::abs(v_end - v_nominal), 1e-6) << "the changed gain changes the result";
    }
  }
}

// Voltage inputs on the UR5 twin: held over each communication step as Simulator::setCommand holds them.
TEST(FmuInstance, RobotVoltageInputsMatchSimulatorCommands) {
  fmi::ExportOptions o;
  o.inputs = {"voltage", "elbow_joint:setpoint"};
  EXPECT_THROW(fmi::describe(*experiments::loadExperiment(kUr5), o, "m"), InputError)
      << "elbow_joint twice (voltage and setpoint)";
  o.inputs = {"shoulder_pan_joint:voltage", "elbow_joint:current"};
  o.outputs = {"q_shoulder_pan_joint", "current_elbow_joint[A]"};
  Resources r(kUr5, o, "ur5");
  ASSERT_EQ(r.d.variables[0].name, "cmd_voltage_shoulder_pan_joint");
  ASSERT_EQ(r.d.variables[0].unit, "V");
  ASSERT_EQ(r.d.variables[1].name, "cmd_current_elbow_joint");
  ASSERT_EQ(r.d.variables[2].name, "q_shoulder_pan_joint");
  ASSERT_EQ(r.d.variables[3].unit, "A");
  Log log;
  fmi::Instance inst("ur5", r.dir.string(), r.d.guid, log.logger());
  ASSERT_EQ(inst.enterInitializationMode(), fmi::Status::OK) << (log.lines.empty() ? "" : log.lines.back());
  ASSERT_EQ(inst.exitInitializationMode(), fmi::Status::OK);
  auto e = std::shared_ptr<experiments::Experiment>(experiments::loadExperiment(kUr5));
  auto sim = experiments::makeSimulator(e);
  const auto& robot = dynamic_cast<const systems::RobotSystem&>(sim->plant());
  robot.setCommandPort(sim->plantState(), 0, systems::CommandPort::Voltage);
  robot.setCommandPort(sim->plantState(), 2, systems::CommandPort::Current);
  const unsigned in[2] = {0, 1}, out[2] = {2, 3};
  double t = 0.0, dev = 0.0, q_start = 0.0, q_end = 0.0;
  for (int k = 0; k < 100; ++k) {
    const double u[2] = {2.0 * std::sin(20.0 * t), 0.5};
    ASSERT_EQ(inst.setReal(in, 2, u), fmi::Status::OK);
    robot.setCommand(sim->plantState(), 0, u[0]);
    robot.setCommand(sim->plantState(), 2, u[1]);
    ASSERT_EQ(inst.doStep(t, 1e-3), fmi::Status::OK) << (log.lines.empty() ? "" : log.lines.back());
    t = sim->advance(1e-3);
    double y[2];
    ASSERT_EQ(inst.getReal(out, 2, y), fmi::Status::OK);
    dev = std::max({dev, std::abs(y[0] - sim->signal("q_shoulder_pan_joint")),
                    std::abs(y[1] - sim->signal("current_elbow_joint"))});
    if (k == 0) q_start = y[0];
    q_end = y[0];
  }
  EXPECT_LE(dev, 1e-12);
  EXPECT_GT(std::abs(q_end - q_start), 1e-6) << "the voltage input moves the joint";
}

TEST(FmuInstance, BadCallsReturnErrorsAndLog) {
  fmi::ExportOptions o;
  o.inputs = {"command"};
  Resources r(kRig, o, "bad");
  Log log;
  EXPECT_THROW(fmi::Instance("x", r.dir.string(), "{wrong}", log.logger()), InputError);
  EXPECT_THROW(fmi::Instance("x", (r.dir / "missing").string(), r.d.guid, log.logger()), InputError);

  fmi::Instance inst("bad", r.dir.string(), r.d.guid, log.logger());
  EXPECT_EQ(inst.doStep(0.0, 1e-3), fmi::Status::Error);
  EXPECT_TRUE(log.mentions("fmi2DoStep is not allowed in state instantiated"));
  const unsigned unknown = 100000;
  double v = 0.0;
  EXPECT_EQ(inst.getReal(&unknown, 1, &v), fmi::Status::Error);
  EXPECT_TRUE(log.mentions("unknown value reference 100000"));
  const unsigned vr_in = vrOf(r.d, "cmd_input");
  const double nan = std::nan("");
  EXPECT_EQ(inst.setReal(&vr_in, 1, &nan), fmi::Status::Error);
  EXPECT_TRUE(log.mentions("cmd_input = nan is not finite"));
  // A parameter value the loader rejects: the message of --set, and the instance keeps its previous value.
  const unsigned vr_inertia = vrOf(r.d, "load.inertia");
  const double negative = -1.0;
  EXPECT_EQ(inst.setReal(&vr_inertia, 1, &negative), fmi::Status::Error);
  EXPECT_TRUE(log.mentions("load.inertia")) << log.lines.back();
  EXPECT_EQ(inst.getReal(&vr_inertia, 1, &v), fmi::Status::OK);
  EXPECT_EQ(v, 1.279);

  ASSERT_EQ(inst.enterInitializationMode(), fmi::Status::OK);
  ASSERT_EQ(inst.exitInitializationMode(), fmi::Status::OK);
  const double one = 1.0;
  EXPECT_EQ(inst.setReal(&vr_inertia, 1, &one), fmi::Status::Error);
  EXPECT_TRUE(log.mentions("parameter load.inertia is fixed"));
  EXPECT_EQ(inst.doStep(0.0, -1e-3), fmi::Status::Error);
  EXPECT_EQ(inst.doStep(0.0, nan), fmi::Status::Error);
  EXPECT_EQ(inst.doStep(0.0, 1e-300), fmi::Status::Error);  // below the time resolution: refused, not a failure
  EXPECT_TRUE(log.mentions("below the time resolution"));
  EXPECT_EQ(inst.doStep(0.5, 1e-3), fmi::Status::Error);
  EXPECT_TRUE(log.mentions("communication point 0.5 s, but the FMU is at 0 s"));
  EXPECT_EQ(inst.doStep(0.0, 1e-3), fmi::Status::OK) << "the rejected calls changed nothing";

  EXPECT_EQ(inst.terminate(), fmi::Status::OK);
  EXPECT_EQ(inst.doStep(1e-3, 1e-3), fmi::Status::Error);
  EXPECT_EQ(inst.reset(), fmi::Status::OK);
  ASSERT_EQ(inst.enterInitializationMode(), fmi::Status::OK);
  ASSERT_EQ(inst.exitInitializationMode(), fmi::Status::OK);
  EXPECT_EQ(inst.doStep(0.0, 1e-3), fmi::Status::OK);
}

TEST(FmuDescription, JsonRoundTripAndModelDescription) {
  fmi::ExportOptions o;
  o.inputs = {"setpoint"};
  auto e = experiments::loadExperiment(kUr5);
  fmi::FmuDescription d = fmi::describe(*e, o, "ur5_twin");
  d.guid = "{g}";
  const fmi::FmuDescription back = fmi::FmuDescription::fromJson(d.toJson(), "test");
  ASSERT_EQ(back.variables.size(), d.variables.size());
  for (size_t i = 0; i < d.variables.size(); ++i) {
    EXPECT_EQ(back.variables[i].name, d.variables[i].name);
    EXPECT_EQ(back.variables[i].start, d.variables[i].start);
    EXPECT_EQ(back.variables[i].key, d.variables[i].key);
  }
  EXPECT_EQ(d.variables[0].name, "cmd_q_shoulder_pan_joint");
  EXPECT_EQ(d.variables[1].name, "cmd_qd_shoulder_pan_joint");
  EXPECT_EQ(d.variables[2].name, "cmd_qdd_shoulder_pan_joint");
  EXPECT_EQ(d.variables[1].unit, "rad/s");
  EXPECT_EQ(d.variables[2].unit, "rad/s2");
  EXPECT_EQ(d.variables[3].name, "cmd_q_shoulder_lift_joint");
  EXPECT_NEAR(d.variables[0].start, 0.0, 1e-12);  // the trajectory's offset of joint 1
  EXPECT_NEAR(d.variables[3].start, -1.2, 1e-12);
  const std::string xml = d.modelDescriptionXml();
  EXPECT_NE(xml.find("<Unit name=\"N.m\"><BaseUnit kg=\"1\" m=\"2\" s=\"-2\"/></Unit>"), std::string::npos);
  for (const fmi::Variable& v : d.variables) {  // ASCII unit names (N.m, rad/s2); no parameter without effect
    for (const char c : v.unit) EXPECT_GE(static_cast<unsigned char>(c), 0x20) << v.name << " [" << v.unit << "]";
    for (const char c : v.unit) EXPECT_LT(static_cast<unsigned char>(c), 0x80) << v.name << " [" << v.unit << "]";
    EXPECT_NE(v.key, "duration");
  }
  EXPECT_NE(xml.find("unit=\"N.m\""), std::string::npos);
  EXPECT_EQ(fmi::fmuUnit("kg·m²"), "kg.m2");
  EXPECT_EQ(fmi::fmuUnit("N·m·s/rad"), "N.m.s/rad");
  EXPECT_EQ(fmi::fmuUnit("Ω"), "Ohm");
  EXPECT_NE(xml.find("name=\"trajectory.a[0,1]\""), std::string::npos);  // key trajectory.a[0][1]
  EXPECT_NE(xml.find("stopTime=\"10\""), std::string::npos);
  nlohmann::ordered_json bad = d.toJson();
  bad["variables"][0].erase("key");
  EXPECT_THROW(fmi::FmuDescription::fromJson(bad, "test"), InputError);
  fmi::ExportOptions wrong;
  wrong.inputs = {"torque"};
  EXPECT_THROW(fmi::describe(*e, wrong, "m"), InputError);
  wrong.inputs = {"no_such_joint:voltage"};
  EXPECT_THROW(fmi::describe(*e, wrong, "m"), InputError);
  wrong.inputs = {};
  wrong.outputs = {"no_such_signal"};
  EXPECT_THROW(fmi::describe(*e, wrong, "m"), InputError);
}

// A solver failure inside fmi2DoStep: fmi2Error, a log naming the simulated time and the component, and then
// only reset, terminate and free. The rig's own file with a step budget of 20 per call (solver.max_num_steps).
TEST(FmuInstance, SolverFailureIsReportedWithTimeAndComponent) {
  const test::TempDir tmp("fail_cfg");
  const fs::path& dir = tmp.path();
  {
    std::ifstream in(kRig);
    std::stringstream text;
    text << in.rdbuf();
    std::string yaml = text.str();
    const std::string from = "solver: {method: bdf,";
    const auto at = yaml.find(from);
    ASSERT_NE(at, std::string::npos);
    yaml.replace(at, from.size(), "solver: {max_num_steps: 20, method: bdf,");
    std::ofstream(dir / "rig.yaml") << yaml;
  }
  fmi::ExportOptions o;
  Resources r((dir / "rig.yaml").string(), o, "fail");
  Log log;
  fmi::Instance inst("fail", r.dir.string(), r.d.guid, log.logger());
  ASSERT_EQ(inst.enterInitializationMode(), fmi::Status::OK);
  ASSERT_EQ(inst.exitInitializationMode(), fmi::Status::OK);
  fmi::Status s = fmi::Status::OK;
  double t = 0.0;
  for (int k = 0; k < 2000 && s == fmi::Status::OK; ++k) {
    s = inst.doStep(t, 1e-3);
    t += 1e-3;
  }
  ASSERT_EQ(s, fmi::Status::Error) << "20 steps per communication step cannot follow the velocity ramp";
  EXPECT_TRUE(log.mentions("fmi2DoStep: solver failure at t = ")) << log.lines.back();
  std::printf("%s\n", log.lines.back().c_str());
  EXPECT_TRUE(log.mentions("joint rig")) << log.lines.back();
  EXPECT_EQ(inst.doStep(inst.time(), 1e-3), fmi::Status::Error);
  EXPECT_TRUE(log.mentions("not allowed in state failed"));
  EXPECT_EQ(inst.reset(), fmi::Status::OK);
  const unsigned vr = vrOf(r.d, "solver.max_num_steps");
  const double many = 100000;
  ASSERT_EQ(inst.setReal(&vr, 1, &many), fmi::Status::OK);
  ASSERT_EQ(inst.enterInitializationMode(), fmi::Status::OK);
  ASSERT_EQ(inst.exitInitializationMode(), fmi::Status::OK);
  for (int k = 0; k < 1500; ++k) ASSERT_EQ(inst.doStep(k * 1e-3, 1e-3), fmi::Status::OK) << k;
}

// Drive parameters of the UR5 twin's robot file as FMU parameters: the friction factor of one drive acts as the
// fault of the same value (systems::Fault), and only the factors that apply to the drive are offered.
TEST(FmuInstance, DriveParameterActsAsTheSameFault) {
  fmi::ExportOptions o;
  o.outputs = {"friction_torque_elbow_joint", "q_elbow_joint"};
  Resources r(kUr5, o, "drive");
  bool has_backlash = false;
  for (const auto& v : r.d.variables) has_backlash |= v.fault == "backlash_add";
  EXPECT_FALSE(has_backlash) << "strain-wave gears take no added backlash";
  for (const auto& v : r.d.variables)  // faults with time laws (episodes, ripple) have no neutral parameter value
    if (!v.fault.empty()) {
      systems::Fault f;
      f.type = systems::faultTypeFromString(v.fault);
      EXPECT_TRUE(f.parameterFault()) << v.name;
    }
  const unsigned vr = vrOf(r.d, "drives.elbow_joint.coulomb_friction_scale");
  EXPECT_EQ(r.d.variables[vr].start, 1.0);
  Log log;
  fmi::Instance inst("drive", r.dir.string(), r.d.guid, log.logger());
  const double two = 2.0;
  ASSERT_EQ(inst.setReal(&vr, 1, &two), fmi::Status::OK) << (log.lines.empty() ? "" : log.lines.back());
  ASSERT_EQ(inst.enterInitializationMode(), fmi::Status::OK);
  ASSERT_EQ(inst.exitInitializationMode(), fmi::Status::OK);
  systems::Fault f;
  f.type = systems::FaultType::CoulombFrictionScale;
  f.joint = "elbow_joint";
  f.value = 2.0;
  auto faulty =
      experiments::makeSimulator(std::shared_ptr<experiments::Experiment>(experiments::loadExperiment(kUr5, {}, {f})));
  auto nominal =
      experiments::makeSimulator(std::shared_ptr<experiments::Experiment>(experiments::loadExperiment(kUr5)));
  const unsigned out = vrOf(r.d, "friction_torque_elbow_joint");
  double dev = 0.0, diff = 0.0, t = 0.0;
  for (int k = 0; k < 300; ++k) {
    ASSERT_EQ(inst.doStep(t, 1e-3), fmi::Status::OK);
    t = faulty->advance(1e-3);
    nominal->advance(1e-3);
    double tau = 0.0;
    ASSERT_EQ(inst.getReal(&out, 1, &tau), fmi::Status::OK);
    dev = std::max(dev, std::abs(tau - faulty->signal("friction_torque_elbow_joint")));
    diff = std::max(diff, std::abs(tau - nominal->signal("friction_torque_elbow_joint")));
  }
  EXPECT_LE(dev, 1e-12);
  EXPECT_GT(diff, 0.1) << "twice the Coulomb friction changes the friction torque [N·m]";
  const double bad = -1.0;
  EXPECT_EQ(inst.reset(), fmi::Status::OK);
  EXPECT_EQ(inst.setReal(&vr, 1, &bad), fmi::Status::Error);
  EXPECT_TRUE(log.mentions("coulomb_friction_scale")) << log.lines.back();
}

// An edited description under a matching GUID (issue 26: a signal index out of range crashed fmi2GetReal): the
// instance compares every output and input with the plant it loaded and refuses to initialise, with the reason.
TEST(FmuInstance, AnEditedDescriptionIsAnErrorNotACrash) {
  struct Edit {
    const char* what;
    std::string config;
    std::vector<std::string> inputs;
    void (*apply)(fmi::FmuDescription&);
    const char* expected;
  };
  const std::vector<Edit> edits = {
      {"output signal out of range",
       kRig,
       {"command"},
       [](fmi::FmuDescription& d) {
         for (auto& v : d.variables)
           if (v.causality == fmi::Causality::Output) v.signal = 1000000;
       },
       "out of range (the plant has"},
      {"output renumbered",
       kRig,
       {"command"},
       [](fmi::FmuDescription& d) {
         for (auto& v : d.variables)
           if (v.causality == fmi::Causality::Output) {
             v.signal = v.signal == 0 ? 1 : 0;
             break;
           }
       },
       "the FMU's resources were edited"},
      {"negative signal",
       kRig,
       {"command"},
       [](fmi::FmuDescription& d) {
         for (auto& v : d.variables)
           if (v.causality == fmi::Causality::Output) v.signal = -7;
       },
       "malformed FMU description: signal = -7"},  // refused when the description is read
      {"robot input port unknown",
       kUr5,
       {"shoulder_pan_joint:voltage"},
       [](fmi::FmuDescription& d) {
         for (auto& v : d.variables)
           if (v.causality == fmi::Causality::Input) v.port = "shoulder_pan_joint.warp";
       },
       "no input 'shoulder_pan_joint.warp'"},
  };
  for (const Edit& e : edits) {
    SCOPED_TRACE(e.what);
    fmi::ExportOptions o;
    o.inputs = e.inputs;
    Resources r(e.config, o, "edited");
    e.apply(r.d);
    std::ofstream(r.dir / "jointsim_fmu.json") << r.d.toJson().dump(1);
    Log log;
    if (std::string(e.expected).rfind("malformed", 0) == 0) {  // fmi2Instantiate fails (returns no instance)
      try {
        fmi::Instance("edited", r.dir.string(), r.d.guid, log.logger());
        ADD_FAILURE() << "an instance of a malformed description";
      } catch (const InputError& err) {
        EXPECT_NE(std::string(err.what()).find(e.expected), std::string::npos) << err.what();
      }
      continue;
    }
    fmi::Instance inst("edited", r.dir.string(), r.d.guid, log.logger());
    EXPECT_EQ(inst.enterInitializationMode(), fmi::Status::Error);
    EXPECT_TRUE(log.mentions(e.expected)) << (log.lines.empty() ? "" : log.lines.back());
    const std::vector<unsigned> all = [&] {
      std::vector<unsigned> v(r.d.variables.size());
      for (unsigned i = 0; i < v.size(); ++i) v[i] = i;
      return v;
    }();
    std::vector<double> values(all.size());
    EXPECT_EQ(inst.getReal(all.data(), all.size(), values.data()), fmi::Status::Error);  // no simulator, no read
  }
}
