// The FMU: its description resource (resources/jointsim_fmu.json, edited by the input: signal indices, joints, ports,
// causalities, start values, keys, drive faults, the GUID, the experiment file and type, overrides, missing keys and
// wrong types, or cut short) and a sequence of FMI 2.0 Co-Simulation calls driven by the input (setupExperiment,
// enter/exitInitializationMode, setReal/getReal with value references in and out of range and values from 0 to
// NaN, doStep with communication points and step sizes from the input including NaN, inf, 0 and negative ones,
// reset, terminate), either on fmi::Instance or through the C functions of the FMU binary (fmu/fmi2_cosimulation.cpp,
// compiled into this target: fmi2Instantiate with good and bad resource URIs, types and GUIDs, fmi2FreeInstance
// twice and calls after it, the unsupported functions).
//
// Oracle: every call returns a status (OK, Warning or Error; never a crash, an exception or a sanitizer report); the
// constructor of fmi::Instance throws only jointsim::Error; a successful doStep ends exactly at the communication
// point; a value set by a successful setReal reads back unchanged; after fmi2FreeInstance every call on the handle
// returns fmi2Error. The experiment is the joint rig config/experiments/ur5_swg_joint_velocity.yaml (or, for one input
// in eight, the UR5 twin under setpoint and voltage inputs: at most 4 steps of at most 2 ms) with at most 2000 solver
// steps per doStep, at most 20 steps of at most 10 ms per input. Each input's resources are in a folder of its own (mkdtemp), removed afterwards.
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fmi2Functions.h"
#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/fmi/fmu.hpp"

namespace {

namespace fs = std::filesystem;
namespace fuzz = jointsim::fuzz;
using jointsim::fmi::Status;
using Json = nlohmann::ordered_json;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// [[noreturn]] with a message: what the oracle caught.
[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_fmu: %s\n", what.c_str());
  __builtin_trap();
}

// The two descriptions the inputs start from, as the exporter writes them (experiment_file relative to a resources
// folder directly inside the workspace).
struct Base {
  Json json;
  size_t max_steps;  // doStep calls per input
  double max_h;      // [s] the longest ordinary communication step
};

const std::vector<Base>& bases() {
  static const std::vector<Base> b = [] {
    using namespace jointsim;
    std::vector<Base> out;
    auto make = [&](const char* file, std::vector<std::string> inputs, std::vector<std::string> overrides,
                    size_t max_steps, double max_h) {
      const std::string config = (fuzz::workspace() / "config/experiments" / file).string();
      fmi::ExportOptions o;
      o.inputs = std::move(inputs);
      o.overrides = std::move(overrides);
      auto e = experiments::loadExperiment(config, o.overrides);
      fmi::FmuDescription d = fmi::describe(*e, o, "fz");
      d.overrides = o.overrides;
      d.guid = std::string("{fuzz-") + file + "}";
      d.experiment_file = std::string("../config/experiments/") + file;
      out.push_back({d.toJson(), max_steps, max_h});
    };
    // Each doStep at most 2000 internal solver steps (the instance's limit per communication step; the rig takes
    // about 300 for 10 ms), so that no parameter value the input sets (a tight rtol, a stiff gear) makes an input slow.
    make("ur5_swg_joint_velocity.yaml", {"command"}, {"+solver.max_num_steps=2000"}, 20, 1e-2);
    make("ur5_excitation.yaml", {"elbow_joint:setpoint", "wrist_1_joint:voltage"},
         {"+solver.max_num_steps=2000", "duration=0.05"}, 4, 2e-3);
    return out;
  }();
  return b;
}

// ---------------------------------------------------------------------------------------------- the description
Json intValue(fuzz::Bytes& in, size_t nv) {
  switch (in.pick(19)) {
    case 0: return -1;
    case 1: return 0;
    case 2: return 1;
    case 3: return 2;
    case 4: return 3;
    case 5: return static_cast<int>(nv) - 1;
    case 6: return static_cast<int>(nv);
    case 7: return 1000000;
    case 8: return std::numeric_limits<int>::max();
    case 9: return std::numeric_limits<int>::min();
    case 10: return 4294967297ull;
    case 11: return -4294967297ll;
    case 12: return 2.5;
    case 13: return -2.5;
    case 14: return "1";
    case 15: return nullptr;
    case 16: return 1e20;  // beyond every int
    case 17: return -1e10;
    default: return in.byte();
  }
}

Json realValue(fuzz::Bytes& in) {
  switch (in.pick(12)) {
    case 0: return 0.0;
    case 1: return -1.0;
    case 2: return 1e308;
    case 3: return -1e308;
    case 4: return 5e-324;
    case 5: return 1.279;
    case 6: return 20.0;
    case 7: return "x";
    case 8: return nullptr;
    case 9: return true;
    case 10: return 0.5;
    default: return static_cast<double>(static_cast<int8_t>(in.byte()));
  }
}

void mutate(Json& j, fuzz::Bytes& in) {
  static const char* const kPorts[] = {"input", "voltage", "current", "motor_torque", "motor_velocity", "setpoint",
                                       "q",     "qd",      "",        "bogus"};
  static const char* const kCausality[] = {"input", "output", "parameter", "local", ""};
  static const char* const kKeys[] = {"load.inertia",
                                      "input.controller.ki",
                                      "solver.rtol",
                                      "duration",
                                      "nonexistent",
                                      "",
                                      "input.profile.values[1]",
                                      "friction.model.f_c",
                                      "+x",
                                      "a=b",
                                      "solver.max_order",
                                      "transmission.size"};
  static const char* const kFaults[] = {"",      "gear_stiffness_scale", "sensor_bias",
                                        "bogus", "backlash_add",         "sensor_dropout"};
  static const char* const kNames[] = {"",
                                       "x",
                                       "drives.elbow_joint.gear_stiffness_scale",
                                       "drives.gear_stiffness_scale",
                                       "drives.wrist_1_joint.sensor_bias",
                                       "cmd_input",
                                       "output_velocity"};
  static const char* const kFields[] = {"name",  "causality", "unit",   "description", "start",
                                        "joint", "port",      "signal", "key",         "fault"};
  static const char* const kTypes[] = {"joint_rig", "tracking", "clamping", ""};
  static const char* const kFiles[] = {"missing.yaml",
                                       "",
                                       ".",
                                       "/dev/null",
                                       "../config/robots/ur5.yaml",
                                       "../config/experiments/ur5_fall.yaml",
                                       "../config/experiments/ur5_swg_joint_velocity.yaml",
                                       "../config/experiments/ur5_excitation.yaml",
                                       "../config/experiments/"};
  static const char* const kOverrides[] = {"duration=0.01",        "bogus=1",      "=",
                                           "solver.rtol=-1",       "log_rate=1e9", "load.inertia=0",
                                           "+solver.max_step=1e-3"};
  static const char* const kTop[] = {"format",          "model_identifier", "guid",      "experiment_file",
                                     "experiment_type", "description",      "stop_time", "step_size",
                                     "overrides",       "variables"};
  Json& vars = j["variables"];
  const size_t nv = vars.is_array() ? vars.size() : 0;
  const uint8_t kind = in.byte();
  Json* v = nullptr;
  if (nv > 0) v = &vars[in.pick(nv)];
  switch (kind % 16) {
    case 0:
      if (v) (*v)["signal"] = intValue(in, nv);
      break;
    case 1:
      if (v) (*v)["joint"] = intValue(in, nv);
      break;
    case 2:
      if (v) (*v)["port"] = in.pick(kPorts);
      break;
    case 3:
      if (v) (*v)["causality"] = in.pick(kCausality);
      break;
    case 4:
      if (v) (*v)["start"] = realValue(in);
      break;
    case 5:
      if (v) (*v)["key"] = in.pick(kKeys);
      break;
    case 6:
      if (v) (*v)["fault"] = in.pick(kFaults);
      break;
    case 7:
      if (v) (*v)["name"] = in.pick(kNames);
      break;
    case 8:
      if (v) v->erase(in.pick(kFields));
      break;
    case 9:
      if (v) vars.push_back(Json(*v));
      break;
    case 10:
      if (v) vars.erase(vars.begin() + static_cast<std::ptrdiff_t>(in.pick(nv)));
      break;
    case 11: j["experiment_type"] = in.pick(kTypes); break;
    case 12: j["experiment_file"] = in.pick(kFiles); break;
    case 13:
      if (j["overrides"].is_array()) j["overrides"].push_back(in.pick(kOverrides));
      break;
    case 14: j[in.pick(kTop)] = realValue(in); break;  // a number, a string, null or true where anything is expected
    default: j["guid"] = in.pick(kFiles); break;
  }
}

// ---------------------------------------------------------------------------------------------- the calls
// A value for setReal or a start time.
double realArg(fuzz::Bytes& in) {
  static const double kValues[] = {0.0, 1.0,  -1.0,  0.5,    1e-3,   1.279, 20.0, 48.0,  -48.0,
                                   1e6, -1e6, 1e300, -1e300, 5e-324, kNan,  kInf, -kInf, 1e-9};
  const uint8_t b = in.byte();
  if (b < 128) return static_cast<double>(static_cast<int8_t>(in.byte())) / 16.0;
  return kValues[b % (sizeof kValues / sizeof kValues[0])];
}

// A step size: up to max_h, or one of the sizes a doStep must refuse (or survive).
double stepArg(fuzz::Bytes& in, double max_h) {
  static const double kOdd[] = {0.0, -1e-3, kNan, kInf, -kInf, 1e-300, 1e-12, -0.0};
  const uint8_t b = in.byte();
  if (b < 224) return max_h * (1 + in.byte()) / 256.0;
  return kOdd[b % (sizeof kOdd / sizeof kOdd[0])];
}

// One call interface over fmi::Instance or the C functions: each call returns the FMI status as an int.
struct CppApi {
  jointsim::fmi::Instance* inst;
  int setup(bool tol_defined, double tol, double start, bool stop_defined, double stop) {
    return static_cast<int>(inst->setupExperiment(tol_defined, tol, start, stop_defined, stop));
  }
  int enter() { return static_cast<int>(inst->enterInitializationMode()); }
  int exit() { return static_cast<int>(inst->exitInitializationMode()); }
  int terminate() { return static_cast<int>(inst->terminate()); }
  int reset() { return static_cast<int>(inst->reset()); }
  int getReal(const unsigned* vr, size_t n, double* v) { return static_cast<int>(inst->getReal(vr, n, v)); }
  int setReal(const unsigned* vr, size_t n, const double* v) { return static_cast<int>(inst->setReal(vr, n, v)); }
  int doStep(double t, double h) { return static_cast<int>(inst->doStep(t, h)); }
  double time() { return inst->time(); }
  bool freed() const { return false; }
  void extra(fuzz::Bytes&) {}
};

void cLogger(fmi2ComponentEnvironment, fmi2String instance, fmi2Status, fmi2String category, fmi2String message, ...) {
  if (category == nullptr || message == nullptr) fail("the C layer logged without a category or message");
  char buf[512];
  va_list args;
  va_start(args, message);
  std::vsnprintf(buf, sizeof buf, message, args);
  va_end(args);
  (void)instance;
  fuzz::note(buf);
}

struct CApi {
  fmi2Component c;
  bool is_freed = false;
  int check(fmi2Status s) {
    if (is_freed && s != fmi2Error) fail("a call on a freed instance did not return fmi2Error");
    return static_cast<int>(s);
  }
  int setup(bool tol_defined, double tol, double start, bool stop_defined, double stop) {
    return check(fmi2SetupExperiment(c, tol_defined, tol, start, stop_defined, stop));
  }
  int enter() { return check(fmi2EnterInitializationMode(c)); }
  int exit() { return check(fmi2ExitInitializationMode(c)); }
  int terminate() { return check(fmi2Terminate(c)); }
  int reset() { return check(fmi2Reset(c)); }
  int getReal(const unsigned* vr, size_t n, double* v) { return check(fmi2GetReal(c, vr, n, v)); }
  int setReal(const unsigned* vr, size_t n, const double* v) { return check(fmi2SetReal(c, vr, n, v)); }
  int doStep(double t, double h) { return check(fmi2DoStep(c, t, h, fmi2True)); }
  double time() {
    double t = kNan;
    return fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &t) == fmi2OK ? t : kNan;
  }
  bool freed() const { return is_freed; }
  // The rest of the C interface: other types, FMU states, status queries, logging, and freeing (twice).
  void extra(fuzz::Bytes& in) {
    const fmi2ValueReference vr[2] = {0, in.byte()};
    fmi2Integer ints[2] = {};
    fmi2Boolean bools[2] = {};
    fmi2String strings[2] = {"a", "b"};
    const size_t n = 1 + in.pick(2);  // (no values of another type: a count of 0 is fmi2OK on any handle)
    switch (in.pick(12)) {
      case 0: check(fmi2GetInteger(c, vr, n, ints)); break;
      case 1: check(fmi2SetBoolean(c, vr, n, bools)); break;
      case 2: check(fmi2GetString(c, vr, n, strings)); break;
      case 3: check(fmi2SetDebugLogging(c, in.flag(), 0, nullptr)); break;
      case 4: {  // FMU states: get, serialise, edit the bytes, deserialise, set (or not), free every one made
        fmi2FMUstate state = nullptr, back = nullptr;
        check(fmi2GetFMUstate(c, &state));
        size_t size = 0;
        if (state != nullptr && fmi2SerializedFMUstateSize(c, state, &size) == fmi2OK && size < (1U << 24)) {
          std::vector<char> bytes(size);
          check(fmi2SerializeFMUstate(c, state, bytes.data(), bytes.size()));
          if (!bytes.empty() && in.flag()) bytes[in.u32() % bytes.size()] = static_cast<char>(in.byte());
          if (in.flag()) bytes.resize(in.u32() % (bytes.size() + 1));
          check(fmi2DeSerializeFMUstate(c, bytes.data(), bytes.size(), &back));
        }
        if (in.flag()) check(fmi2SetFMUstate(c, back != nullptr ? back : state));
        check(fmi2FreeFMUstate(c, &back));
        check(fmi2FreeFMUstate(c, &state));
        break;
      }
      case 5: {
        fmi2Status s = fmi2OK;
        check(fmi2GetStatus(c, fmi2DoStepStatus, &s));
        break;
      }
      case 6: {
        fmi2Real r = 0.0;
        check(fmi2GetRealStatus(c, in.flag() ? fmi2LastSuccessfulTime : fmi2DoStepStatus, &r));
        check(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, nullptr));
        break;
      }
      case 7: check(fmi2CancelStep(c)); break;
      case 8: check(fmi2SetRealInputDerivatives(c, vr, n, ints, nullptr)); break;
      case 9:
      case 10:
        fmi2FreeInstance(c);  // a second time is a no-op, as is any call after it (fmi2Error)
        is_freed = true;
        break;
      default: check(fmi2GetReal(c, vr, n, nullptr)); break;
    }
  }
};

// `capped`: the value references of the parameter solver.max_num_steps (the bound on the work of one doStep that the
// harness adds at export), which setReal may lower but not raise above 2000.
template <class Api>
void exercise(Api& api, fuzz::Bytes& in, size_t n_vars, const std::vector<unsigned>& capped, const Base& base) {
  size_t steps = 0;
  for (int op = 0; op < 48 && in.left() > 0; ++op) {
    int s = 0;
    const uint8_t code = in.byte();
    switch (code % 12) {
      case 0: {
        const bool tol = in.flag();
        const double tolerance = realArg(in), start = realArg(in);
        s = api.setup(tol, tolerance, start, in.flag(), realArg(in));
        break;
      }
      case 1: s = api.enter(); break;
      case 2: s = api.exit(); break;
      case 3:
      case 4: {  // setReal of 0 to 3 values, value references in range or not, then read back
        const size_t n = in.pick(4);
        std::vector<unsigned> vr(n);
        std::vector<double> v(n);
        for (size_t k = 0; k < n; ++k) {
          const uint8_t r = in.byte();
          vr[k] = r < 240 ? static_cast<unsigned>(r % (n_vars + 2)) : r < 250 ? 0xffffffffu : 100000u + r;
          v[k] = realArg(in);
          for (const unsigned c : capped)
            if (vr[k] == c && std::isfinite(v[k]) && v[k] > 2000.0) v[k] = 2000.0;
        }
        s = api.setReal(vr.data(), n, v.data());
        if (s == static_cast<int>(Status::OK) && n > 0) {
          std::vector<double> back(n, kNan);
          if (api.getReal(vr.data(), n, back.data()) == static_cast<int>(Status::OK))
            for (size_t k = 0; k < n; ++k) {
              bool last = true;  // a value reference given twice holds the last value set
              for (size_t m = k + 1; m < n; ++m) last = last && vr[m] != vr[k];
              if (last && back[k] != v[k]) fail("setReal then getReal of value reference " + std::to_string(vr[k]));
            }
        }
        break;
      }
      case 5:
      case 6: {  // getReal
        const size_t n = in.pick(5);
        std::vector<unsigned> vr(n);
        for (size_t k = 0; k < n; ++k) {
          const uint8_t r = in.byte();
          vr[k] = r < 240 ? static_cast<unsigned>(r % (n_vars + 2)) : 0x80000000u + r;
        }
        std::vector<double> v(n);
        s = api.getReal(vr.data(), n, v.data());
        break;
      }
      case 7:
      case 8:
      case 9: {  // doStep from the current time (or a wrong communication point)
        if (steps >= base.max_steps) break;
        const double now = api.time();
        double t = now;
        switch (in.pick(8)) {
          case 0: t = now + 0.5; break;
          case 1: t = realArg(in); break;
          default: break;
        }
        const double h = stepArg(in, base.max_h);
        if (std::isfinite(h) && h > 0.0) ++steps;
        s = api.doStep(t, h);
        if (s == static_cast<int>(Status::OK) && !api.freed()) {
          const double after = api.time();
          if (after != now + h)
            fail("doStep(" + std::to_string(t) + ", " + std::to_string(h) + ") from " + std::to_string(now) +
                 " ended at " + std::to_string(after));
        }
        break;
      }
      case 10: s = (code & 16) ? api.reset() : api.terminate(); break;
      default:
        if (code & 16) {
          api.extra(in);
        } else {  // null arrays with a count: an error, not a read through NULL
          s = (code & 32) ? api.getReal(nullptr, 1, nullptr) : api.setReal(nullptr, 2, nullptr);
          if (s != static_cast<int>(Status::Error)) fail("a null array was accepted");
        }
        break;
    }
    if (s != static_cast<int>(Status::OK) && s != static_cast<int>(Status::Warning) &&
        s != static_cast<int>(Status::Error))
      fail("a call returned status " + std::to_string(s));
  }
}

std::string fileUri(const std::string& path, int form) {
  switch (form) {
    case 0: return "file://" + path;
    case 1: return "file:" + path;
    case 2: return "file://localhost" + path + "/";
    case 3: {  // every '/' written as %2F, as some importers encode it
      std::string out = "file://";
      for (char ch : path) out += ch == '/' ? std::string("%2F") : std::string(1, ch);
      return out;
    }
    case 4: return "http://example.invalid" + path;  // not a file: URI, refused
    case 5: return path + "%";
    default: return "file://" + path + "%2";
  }
}

}  // namespace

// Input layout (tests/fuzz/seeds/fmu/): byte 0 the mode (bits 0-2 all set: the UR5 twin, else the rig; bit 3 the C
// functions; bit 4 a wrong GUID; bits 5-6 both set: the description cut short at a length from two bytes after the
// edits); byte 1 the number of edits (% 5), each a kind (% 16), a variable and a value selector (mutate); with the C
// functions one byte for fmi2Instantiate's arguments (the URI form % 7, bits 3-7 null name, ModelExchange, null
// GUID, null callbacks, logging on); then the calls, each a code (% 12: see drive) and its arguments.
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace jointsim;
  fuzz::Bytes in(data, size);
  const uint8_t mode = in.byte();
  const Base& base = bases()[(mode & 7) == 7 ? 1 : 0];
  Json j = base.json;
  const size_t edits = in.pick(5);
  for (size_t k = 0; k < edits; ++k) mutate(j, in);
  std::string text = j.dump(1);
  if ((mode >> 5 & 3) == 3) text.resize(in.u16() % (text.size() + 1));  // cut short
  std::string guid = j.contains("guid") && j["guid"].is_string() ? j["guid"].get<std::string>() : std::string();
  if (mode & 16) guid = "{another}";
  const size_t n_vars = j.contains("variables") && j["variables"].is_array() ? j["variables"].size() : 0;
  std::vector<unsigned> capped;
  for (size_t k = 0; k < n_vars; ++k) {
    const Json& v = j["variables"][k];
    if (v.is_object() && v.contains("key") && v["key"] == "solver.max_num_steps")
      capped.push_back(static_cast<unsigned>(k));
  }

  const fs::path dir = fuzz::makeInputDir("fmu");
  std::ofstream(dir / "jointsim_fmu.json", std::ios::binary) << text;
  if (mode & 8) {  // the C functions of the FMU binary
    fmi2CallbackFunctions cb{};
    cb.logger = cLogger;
    const uint8_t how = in.byte();
    const std::string uri = fileUri(dir.string(), how % 7);
    const fmi2Component c =
        fmi2Instantiate((how & 8) ? nullptr : "fz", (how & 16) ? fmi2ModelExchange : fmi2CoSimulation,
                        (how & 32) ? nullptr : guid.c_str(), uri.c_str(), (how & 64) ? nullptr : &cb, fmi2False,
                        (how & 128) ? fmi2True : fmi2False);
    if (c != nullptr) {
      CApi api{c};
      exercise(api, in, n_vars, capped, base);
      fmi2FreeInstance(c);  // a second free when the input freed it already: a no-op
      if (fmi2DoStep(c, 0.0, 1e-3, fmi2True) != fmi2Error) fail("fmi2DoStep after fmi2FreeInstance");
    }
  } else {
    std::unique_ptr<fmi::Instance> inst;
    try {  // the constructor throws jointsim::Error for a description it cannot use; the calls never throw
      inst = std::make_unique<fmi::Instance>("fz", dir.string(), guid,
                                             [](Status, const char* category, const std::string& message) {
                                               if (category == nullptr || message.empty())
                                                 fail("a log message without category or text");
                                               fuzz::note(message.c_str());
                                             });
    } catch (const Error& e) {
      fuzz::note(e);
    }
    if (inst) {
      CppApi api{inst.get()};
      exercise(api, in, n_vars, capped, base);
    }
  }
  fuzz::removeDir(dir);
  return 0;
}
