// The C functions of the FMI 2.0 Co-Simulation standard for the jointsim FMU binary: each forwards to
// fmi::Instance (include/jointsim/fmi/fmu.hpp), which implements the state machine and never throws; this layer
// adds the checks of the C interface (null instance, the resource URI) and catches anything left (out of memory),
// so that no exception crosses into the importer.
#include <cctype>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <set>
#include <string>

#include "fmi2Functions.h"
#include "jointsim/common/error.hpp"
#include "jointsim/fmi/fmu.hpp"

namespace {

using jointsim::fmi::Instance;
using jointsim::fmi::Status;

struct Component {
  std::string name;
  fmi2CallbackFunctions callbacks{};
  bool logging = true;
  std::set<std::string> categories{"logInfo", "logWarning", "logError"};  // fmi2SetDebugLogging's selection
  std::unique_ptr<Instance> instance;
  // The FMU states made by this instance and not yet freed: a pointer not among them is refused (not dereferenced),
  // and those left are freed with the instance.
  std::set<Instance::State*> states;
  Component() = default;
  Component(const Component&) = delete;
  Component& operator=(const Component&) = delete;
  ~Component() {
    for (Instance::State* s : states) Instance::freeState(s);
  }
};

/// The instances made by fmi2Instantiate and not yet freed: a handle that is not among them (freed twice, used after
/// fmi2FreeInstance, never made) gets fmi2Error instead of touching freed memory.
std::mutex g_live_mutex;
std::set<const void*> g_live;

Component* live(fmi2Component c) {
  const std::lock_guard<std::mutex> lock(g_live_mutex);
  return c != nullptr && g_live.count(c) ? static_cast<Component*>(c) : nullptr;
}

void emit(const fmi2CallbackFunctions& cb, const std::string& name, fmi2Status status, const char* category,
          const std::string& message) {
  if (cb.logger != nullptr) cb.logger(cb.componentEnvironment, name.c_str(), status, category, "%s", message.c_str());
}

/// The state `state` of instance `c` (null if it is not one of its live states: the call is refused, the pointer is
/// not dereferenced).
Instance::State* ownState(fmi2Component c, fmi2FMUstate state);
fmi2Status refuseState(fmi2Component c, const char* call);

fmi2Status toC(Status s) { return static_cast<fmi2Status>(static_cast<int>(s)); }

/// file:///a/b, file:/a/b or file://localhost/a/b -> /a/b with %XX decoded; "" for another scheme.
std::string pathFromUri(const char* uri) {
  if (uri == nullptr) return {};
  std::string u = uri;
  if (u.rfind("file://localhost/", 0) == 0)
    u = u.substr(16);
  else if (u.rfind("file:///", 0) == 0)
    u = u.substr(7);
  else if (u.rfind("file:/", 0) == 0)
    u = u.substr(5);
  else
    return {};
  std::string out;
  for (size_t i = 0; i < u.size(); ++i) {
    if (u[i] == '%' && i + 2 < u.size() + 0 && std::isxdigit(static_cast<unsigned char>(u[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(u[i + 2]))) {
      out += static_cast<char>(std::stoi(u.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += u[i];
    }
  }
  while (out.size() > 1 && out.back() == '/') out.pop_back();
  return out;
}

template <class F>
fmi2Status call(fmi2Component c, const char* what, F&& f) {
  Component* comp = live(c);
  if (comp == nullptr || !comp->instance) return fmi2Error;
  try {
    return toC(f(*comp->instance));
  } catch (const std::exception& e) {
    emit(comp->callbacks, comp->name, fmi2Error, "logError", std::string(what) + ": " + e.what());
  } catch (...) {
    emit(comp->callbacks, comp->name, fmi2Error, "logError", std::string(what) + ": unknown error");
  }
  return fmi2Error;
}

fmi2Status unsupported(fmi2Component c, const char* what) {
  Component* comp = live(c);
  if (comp != nullptr)
    emit(comp->callbacks, comp->name, fmi2Error, "logError", std::string(what) + " is not supported by this FMU");
  return fmi2Error;
}

Instance::State* ownState(fmi2Component c, fmi2FMUstate state) {
  Component* comp = live(c);
  if (comp == nullptr || state == nullptr) return nullptr;
  auto* s = static_cast<Instance::State*>(state);
  return comp->states.count(s) ? s : nullptr;
}

fmi2Status refuseState(fmi2Component c, const char* call) {
  if (Component* comp = live(c))
    emit(comp->callbacks, comp->name, fmi2Error, "logError",
         std::string(call) + ": not an FMU state of this instance (freed, or never made by it)");
  return fmi2Error;
}

}  // namespace

extern "C" {

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                              fmi2Boolean /*visible*/, fmi2Boolean loggingOn) {
  fmi2CallbackFunctions cb{};
  if (functions != nullptr) cb = *functions;
  const std::string name = instanceName != nullptr ? instanceName : "";
  try {
    if (fmuType != fmi2CoSimulation) {
      emit(cb, name, fmi2Error, "logError", "this FMU supports Co-Simulation only");
      return nullptr;
    }
    const std::string resources = pathFromUri(fmuResourceLocation);
    if (resources.empty()) {
      emit(cb, name, fmi2Error, "logError",
           std::string("fmuResourceLocation '") + (fmuResourceLocation ? fmuResourceLocation : "(null)") +
               "' is not a file: URI");
      return nullptr;
    }
    auto comp = std::make_unique<Component>();
    comp->name = name;
    comp->callbacks = cb;
    comp->logging = loggingOn != fmi2False;
    Component* raw = comp.get();
    comp->instance =
        std::make_unique<Instance>(name, resources, fmuGUID != nullptr ? fmuGUID : "",
                                   [raw](Status s, const char* category, const std::string& message) {
                                     if ((raw->logging && raw->categories.count(category)) || s >= Status::Error)
                                       emit(raw->callbacks, raw->name, toC(s), category, message);
                                   });
    {
      const std::lock_guard<std::mutex> lock(g_live_mutex);
      g_live.insert(raw);
    }
    return comp.release();
  } catch (const std::exception& e) {
    emit(cb, name, fmi2Error, "logError", std::string("fmi2Instantiate: ") + e.what());
  } catch (...) {
    emit(cb, name, fmi2Error, "logError", "fmi2Instantiate: unknown error");
  }
  return nullptr;
}

void fmi2FreeInstance(fmi2Component c) {
  {
    const std::lock_guard<std::mutex> lock(g_live_mutex);
    if (c == nullptr || g_live.erase(c) == 0) return;  // not an instance of ours (any more): nothing to free
  }
  delete static_cast<Component*>(c);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
  Component* comp = live(c);
  if (comp == nullptr) return fmi2Error;
  // No categories: all of them (on or off); else exactly those given, each one of <LogCategories>.
  std::set<std::string> chosen{"logInfo", "logWarning", "logError"};
  if (nCategories > 0) {
    if (categories == nullptr) return fmi2Error;
    chosen.clear();
    for (size_t k = 0; k < nCategories; ++k) {
      const std::string name = categories[k] != nullptr ? categories[k] : "";
      if (name != "logInfo" && name != "logWarning" && name != "logError") {
        emit(comp->callbacks, comp->name, fmi2Error, "logError",
             "fmi2SetDebugLogging: unknown log category '" + name + "' (the FMU's are logInfo, logWarning, logError)");
        return fmi2Error;
      }
      chosen.insert(name);
    }
  }
  comp->logging = loggingOn != fmi2False;
  comp->categories = std::move(chosen);
  return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
  return call(c, "fmi2SetupExperiment", [&](Instance& i) {
    return i.setupExperiment(toleranceDefined != fmi2False, tolerance, startTime, stopTimeDefined != fmi2False,
                             stopTime);
  });
}
fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
  return call(c, "fmi2EnterInitializationMode", [](Instance& i) { return i.enterInitializationMode(); });
}
fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
  return call(c, "fmi2ExitInitializationMode", [](Instance& i) { return i.exitInitializationMode(); });
}
fmi2Status fmi2Terminate(fmi2Component c) {
  return call(c, "fmi2Terminate", [](Instance& i) { return i.terminate(); });
}
fmi2Status fmi2Reset(fmi2Component c) {
  return call(c, "fmi2Reset", [](Instance& i) { return i.reset(); });
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
  return call(c, "fmi2GetReal", [&](Instance& i) { return i.getReal(vr, nvr, value); });
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
  return call(c, "fmi2SetReal", [&](Instance& i) { return i.setReal(vr, nvr, value); });
}
// The FMU has Real variables only: any value reference of another type is unknown.
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference[], size_t nvr, fmi2Integer[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetInteger (the FMU has no Integer variables)");
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference[], size_t nvr, fmi2Boolean[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetBoolean (the FMU has no Boolean variables)");
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference[], size_t nvr, fmi2String[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetString (the FMU has no String variables)");
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2Integer[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetInteger (the FMU has no Integer variables)");
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2Boolean[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetBoolean (the FMU has no Boolean variables)");
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2String[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetString (the FMU has no String variables)");
}

// FMU states: Instance::State behind the opaque fmi2FMUstate pointer, owned by the instance's Component.
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state) {
  Component* comp = live(c);
  if (comp == nullptr) return fmi2Error;
  if (state != nullptr && *state != nullptr && ownState(c, *state) == nullptr) return refuseState(c, "fmi2GetFMUstate");
  return call(c, "fmi2GetFMUstate", [&](Instance& i) {
    if (state == nullptr) return i.getState(nullptr);
    auto* s = static_cast<Instance::State*>(*state);
    const Status status = i.getState(&s);
    if (status == Status::OK) {
      comp->states.insert(s);
      *state = s;
    }
    return status;
  });
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
  Instance::State* s = ownState(c, state);
  if (s == nullptr) return refuseState(c, "fmi2SetFMUstate");
  return call(c, "fmi2SetFMUstate", [&](Instance& i) { return i.setState(s); });
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state) {
  Component* comp = live(c);
  if (comp == nullptr) return fmi2Error;
  if (state == nullptr || *state == nullptr) return fmi2OK;
  Instance::State* s = ownState(c, *state);
  if (s == nullptr) return refuseState(c, "fmi2FreeFMUstate");
  comp->states.erase(s);
  Instance::freeState(s);
  *state = nullptr;
  return fmi2OK;
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size) {
  Instance::State* s = ownState(c, state);
  if (s == nullptr) return refuseState(c, "fmi2SerializedFMUstateSize");
  return call(c, "fmi2SerializedFMUstateSize", [&](Instance& i) { return i.serializedSize(s, size); });
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
  Instance::State* s = ownState(c, state);
  if (s == nullptr) return refuseState(c, "fmi2SerializeFMUstate");
  return call(c, "fmi2SerializeFMUstate", [&](Instance& i) { return i.serialize(s, bytes, size); });
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate* state) {
  Component* comp = live(c);
  if (comp == nullptr) return fmi2Error;
  return call(c, "fmi2DeSerializeFMUstate", [&](Instance& i) {
    if (state == nullptr) return i.deserialize(bytes, size, nullptr);
    Instance::State* s = nullptr;
    const Status status = i.deserialize(bytes, size, &s);
    if (status == Status::OK) {
      comp->states.insert(s);
      *state = s;
    }
    return status;
  });
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2ValueReference[],
                                        size_t, const fmi2Real[], fmi2Real[]) {
  return unsupported(c, "fmi2GetDirectionalDerivative");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                       const fmi2Real[]) {
  return unsupported(c, "fmi2SetRealInputDerivatives (canInterpolateInputs is false)");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                        fmi2Real[]) {
  return unsupported(c, "fmi2GetRealOutputDerivatives (maxOutputDerivativeOrder is 0)");
}
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean /*noSetFMUStatePriorToCurrentPoint*/) {
  return call(c, "fmi2DoStep", [&](Instance& i) { return i.doStep(currentCommunicationPoint, communicationStepSize); });
}
fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep (doStep is synchronous)"); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind, fmi2Status*) { return unsupported(c, "fmi2GetStatus"); }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
  Component* comp = live(c);
  if (comp == nullptr || !comp->instance || value == nullptr) return fmi2Error;
  if (s != fmi2LastSuccessfulTime) return unsupported(c, "fmi2GetRealStatus for this status kind");
  *value = comp->instance->time();
  return fmi2OK;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind, fmi2Integer*) {
  return unsupported(c, "fmi2GetIntegerStatus");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind, fmi2Boolean*) {
  return unsupported(c, "fmi2GetBooleanStatus");
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind, fmi2String*) {
  return unsupported(c, "fmi2GetStringStatus");
}

}  // extern "C"
