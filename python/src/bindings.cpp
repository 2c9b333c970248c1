// jointsim._core: Python bindings of the jointsim library (pybind11), the engine of the `jointsim` package
// (python/jointsim/__init__.py holds the user-facing API, its docstrings and argument checks). NumPy float64 arrays
// in and out; every jointsim error becomes an exception of jointsim.errors with the C++ error's fields:
//   InputError → jointsim.InputError (a ValueError: file, line, key_path, message), a missing file →
//   jointsim.InputFileNotFoundError (also a FileNotFoundError), UnidentifiableError → jointsim.UnidentifiableError
//   (a ValueError), SolverError → jointsim.SolverError (a RuntimeError: time, flag, component), a failed
//   conversion of an argument → TypeError, other jointsim errors → RuntimeError.
// Long calls release the GIL and watch for Python's pending signals (Interruptible): Ctrl-C ends them within
// about 20 ms with the KeyboardInterrupt the handler raised.
#include <csignal>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/common/interrupt.hpp"
#include "jointsim/common/version.hpp"
#include "jointsim/experiments/batch.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/fmi/fmu.hpp"
#include "jointsim/identify/clamping_fit.hpp"
#include "jointsim/identify/drive_calibration.hpp"
#include "jointsim/identify/friction_fit.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/io/output.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/report/agreement.hpp"
#include "jointsim/report/dataset.hpp"
#include "jointsim/report/view.hpp"
#include "jointsim/sim/simulate.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/robot_with_drives.hpp"

namespace py = pybind11;
using namespace jointsim;

namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

/// A 1-D float64 view of `a` with `n` entries; InputError naming `what` otherwise.
Eigen::Map<const Eigen::VectorXd> vec(const Array& a, Eigen::Index n, const char* what) {
  if (a.ndim() != 1 || a.shape(0) != n)
    throw InputError(std::string(what) + ": expected an array of shape (" + std::to_string(n) + ",), got shape " +
                     shapeText(a));
  return {a.data(), n};
}

Eigen::VectorXd anyVec(const Array& a, const char* what) {
  if (a.ndim() != 1) throw InputError(std::string(what) + ": expected a 1-D array, got shape " + shapeText(a));
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.shape(0));
}

py::array_t<double> toArray(const Eigen::VectorXd& v) {
  py::array_t<double> out(v.size());
  std::memcpy(out.mutable_data(), v.data(), sizeof(double) * static_cast<size_t>(v.size()));
  return out;
}

py::array_t<double> toArray(const Eigen::MatrixXd& m) {
  py::array_t<double> out({m.rows(), m.cols()});
  auto r = out.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) r(i, j) = m(i, j);
  return out;
}

// ------------------------------------------------------------------------------------------ interruption
/// Python's pending signals, asked from inside a long call (a StopPoll on the calling thread): the handlers run
/// (Ctrl-C's raises KeyboardInterrupt, which stays set as the thread's error) and a failure stops the call.
int pythonSignals(void*) noexcept {
  py::gil_scoped_acquire gil;
  return PyErr_CheckSignals() != 0 ? SIGINT : 0;
}

/// The identifier of the interpreter's main thread, the only one whose signal handlers run (set at import).
unsigned long g_main_thread = 0;

/// Runs `f` without the GIL, stoppable by Python's signal handlers (checked every 20 ms of wall time by the
/// simulation loops): a call that a handler's exception stopped raises that exception (KeyboardInterrupt), not the
/// C++ interruption. Only on the main thread: Python runs signal handlers nowhere else, and a poll there would only
/// contend for the GIL (and a daemon thread taking the GIL while the interpreter shuts down is ended by it).
template <class F>
auto interruptible(F&& f) -> decltype(f()) {
  using R = decltype(f());
  const bool main_thread = PyThread_get_thread_ident() == g_main_thread;
  StopPoll poll(main_thread ? &pythonSignals : nullptr, nullptr, 0.02);
  try {
    if constexpr (std::is_void_v<R>) {
      {
        py::gil_scoped_release release;
        f();
      }
      if (poll.tripped()) throw py::error_already_set();
    } else {
      R r = [&] {
        py::gil_scoped_release release;
        return f();
      }();
      if (poll.tripped()) throw py::error_already_set();
      return r;
    }
  } catch (const py::error_already_set&) {
    throw;
  } catch (...) {
    if (poll.tripped()) throw py::error_already_set();
    throw;
  }
}

// ------------------------------------------------------------------------------------------ errors
/// Sets the Python error to an instance of jointsim.errors.<name>(message, **fields); a plain `fallback` error
/// when that module cannot be imported (the extension used on its own).
void raisePython(const char* name, PyObject* fallback, const std::string& message, const py::dict& fields) {
  try {
    py::object cls = py::module_::import("jointsim.errors").attr(name);
    py::object exc = cls(message, **fields);
    PyErr_SetObject(cls.ptr(), exc.ptr());
  } catch (py::error_already_set&) {
    PyErr_SetString(fallback, message.c_str());
  }
}

// ------------------------------------------------------------------------------------------ threads
/// Two threads in one object at once (one advancing a simulator, which releases the GIL, another setting its
/// commands): a RuntimeError (jointsim.ConcurrentUseError) for the second, never a data race.
class ConcurrentUse : public Error {
 public:
  using Error::Error;
};

/// The lock of one Python object (shared by an Experiment and the simulators made from it: they share a plant).
using Gate = std::shared_ptr<std::mutex>;

/// Holds an object's gate for one call; throws ConcurrentUse when another thread holds it.
class Use {
 public:
  Use(const Gate& gate, const char* what) : lock_(*gate, std::try_to_lock) {
    if (!lock_.owns_lock())
      throw ConcurrentUse(std::string("jointsim.") + what +
                          ": used from two threads at once (another thread is in one of its calls, e.g. advance); give "
                          "each thread its own " +
                          what + ", or hold a lock around its calls");
  }

 private:
  std::unique_lock<std::mutex> lock_;
};

/// A robot model with its own workspace (the Model/Data pair of the C++ API).
struct PyModel {
  explicit PyModel(multibody::Model m) : model(std::move(m)), data(model) {}
  multibody::Model model;
  multibody::Data data;
  Gate gate = std::make_shared<std::mutex>();
  std::vector<std::string> frameNames() const {
    std::vector<std::string> out;
    for (const auto& f : model.frames) out.push_back(f.name);
    return out;
  }
};

int frameOf(const multibody::Model& model, const py::object& frame) {
  if (frame.is_none()) return model.frameIndex(model.tip_frame);
  return model.frameIndex(frame.cast<std::string>());
}

/// States for a rigid-body call: one (shape (nq,)) or a batch (shape (N, nq)), as rows of a row-major matrix.
struct States {
  const double* data;
  py::ssize_t rows;
  bool batch;
};
States states(const Array& a, Eigen::Index n, const char* what) {
  if (a.ndim() == 1 && a.shape(0) == n) return {a.data(), 1, false};
  if (a.ndim() == 2 && a.shape(1) == n) return {a.data(), a.shape(0), true};
  throw InputError(std::string(what) + ": expected an array of shape (" + std::to_string(n) + ",) or (N, " +
                   std::to_string(n) + "), got shape " + shapeText(a));
}
/// The batch size of several state arrays of one call: all of q's shape, (nq,) or (N, nq).
py::ssize_t batchOf(std::initializer_list<std::tuple<const States*, const Array*, const char*>> all) {
  const auto& [first, first_array, first_name] = *all.begin();
  for (const auto& [s, a, what] : all)
    if (s->batch != first->batch || s->rows != first->rows)
      throw InputError(std::string(what) + ": expected the shape of " + first_name + ", " + shapeText(*first_array) +
                       ", got shape " + shapeText(*a));
  return first->rows;
}
Eigen::Map<const Eigen::VectorXd> row(const States& s, py::ssize_t i, Eigen::Index n) { return {s.data + i * n, n}; }

/// f(q, qd, x) → vector of size n per state: one array (n,) or a batch (N, n), the batch without the GIL.
template <class F>
py::array_t<double> perState3(PyModel& p, const Array& a, const Array& b, const Array& c, const char* na,
                              const char* nb, const char* nc, F&& f) {
  const auto n = p.model.nq;
  const States A = states(a, n, na), B = states(b, n, nb), C = states(c, n, nc);
  const py::ssize_t N = batchOf({{&A, &a, na}, {&B, &b, nb}, {&C, &c, nc}});
  if (!A.batch) return toArray(Eigen::VectorXd(f(row(A, 0, n), row(B, 0, n), row(C, 0, n))));
  py::array_t<double> out({N, static_cast<py::ssize_t>(n)});
  double* o = out.mutable_data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < N; ++i)
      Eigen::Map<Eigen::VectorXd>(o + i * n, n) = f(row(A, i, n), row(B, i, n), row(C, i, n));
  }
  return out;
}

/// A loaded experiment (shared with simulators made from it).
struct PyExperiment {
  std::shared_ptr<experiments::Experiment> e;
  Gate gate = std::make_shared<std::mutex>();
};

/// A stepping simulator and its plant.
/// A stepping simulator and its plant. The plant is only read (several simulators may share it, in any threads);
/// the run's state is the simulator's own.
struct PySimulator {
  std::shared_ptr<const sim::Plant> plant;
  const systems::RobotSystem* robot_ptr = nullptr;  // the plant when it is a robot with drives (kept alive by plant)
  std::unique_ptr<sim::Simulator> sim;
  Gate gate = std::make_shared<std::mutex>();

  const systems::RobotSystem& robot() {
    if (!robot_ptr)
      throw InputError(plant->name() + " has no per-joint command ports (only a robot with drives has them; its " +
                       "inputs: Simulator.inputs)");
    return *robot_ptr;
  }
  sim::PlantState& state() { return sim->plantState(); }
  int joint(const py::object& j) {
    const auto& r = robot();
    if (py::isinstance<py::str>(j)) return r.model().jointIndex(j.cast<std::string>());
    if (!py::isinstance<py::int_>(j) || py::isinstance<py::bool_>(j))
      throw py::type_error("joint: expected an index (int) or a joint name (str), got " +
                           std::string(py::str(py::type::of(j).attr("__name__"))));
    const long k = j.cast<long>();
    if (k < 0 || k >= r.dof())
      throw InputError(r.name() + ": joint index " + std::to_string(k) + " out of range 0.." +
                       std::to_string(r.dof() - 1));
    return static_cast<int>(k);
  }
};

/// A snapshot of a simulator: in memory (restored without a copy to bytes), or the bytes of a pickled one.
struct PySnapshot {
  std::shared_ptr<const sim::Snapshot> snapshot;  // null for one made from bytes
  std::shared_ptr<const sim::Plant> plant;        // the snapshot's plant, kept alive (restore compares it)
  std::string bytes;                              // the pickled form (empty until asked for)
  double time = 0.0;
  const std::string& toBytes() {
    if (bytes.empty() && snapshot) bytes = snapshot->toBytes();
    return bytes;
  }
};

sim::CvodeOptions solverFrom(double rtol, double atol, int max_order, double max_step, double max_gamma_change,
                             const std::string& method, double step, const py::object& jacobian_every,
                             const std::string& oscillations) {
  sim::CvodeOptions o;
  o.max_gamma_change = max_gamma_change;
  if (method == "bdf")
    o.method = sim::Method::BDF;
  else if (method == "rosenbrock")
    o.method = sim::Method::Rosenbrock;
  else
    throw InputError("Simulator.from_robot: method: expected 'bdf' or 'rosenbrock' (the fixed-step method), got '" +
                     method + "'");
  if (method != "rosenbrock" && step != 0.0)
    throw InputError("Simulator.from_robot: step: only with method='rosenbrock'");
  o.fixed_step = step;
  if (oscillations != "damp" && oscillations != "resolve")
    throw InputError("Simulator.from_robot: oscillations: expected 'damp' or 'resolve', got '" + oscillations + "'");
  if (method != "rosenbrock" && oscillations != "damp")
    throw InputError("Simulator.from_robot: oscillations: only with method='rosenbrock'");
  o.resolve_oscillations = oscillations == "resolve";  // (before the adaptive Jacobian: its defect depends on it)
  // jacobian_every: a number of steps (a Python int) or 'adaptive' (the Python layer checked the type).
  const bool is_int = py::isinstance<py::int_>(jacobian_every);
  if (!is_int && py::str(jacobian_every).cast<std::string>() == "adaptive") {
    sim::setAdaptiveJacobian(o);
  } else {
    const long every = is_int ? jacobian_every.cast<long>() : 0;
    if (every < 1 || every > sim::kAdaptiveJacobianEvery)
      throw InputError(
          "Simulator.from_robot: jacobian_every: expected a number of steps from 1 to 1e6 or 'adaptive', got '" +
          py::str(jacobian_every).cast<std::string>() + "'");
    o.jacobian_every = static_cast<int>(every);
  }
  o.rtol = rtol;
  o.atol = atol;
  o.max_order = max_order;
  o.max_step = max_step;
  return o;
}

py::dict fitted(const identify::FittedParameter& p) {
  py::dict d;
  d["value"] = p.value;
  d["std_error"] = p.std_error;
  d["fitted"] = p.fitted;
  d["initial"] = p.initial;
  return d;
}

py::dict direction(const identify::DirectionFit& f) {
  py::dict d;
  auto est = [](const identify::ParameterEstimate& p) {
    py::dict e;
    e["value"] = p.value;
    e["std_error"] = p.std_error;
    e["initial"] = p.initial;
    return e;
  };
  d["alpha0"] = est(f.alpha0);
  d["alpha1"] = est(f.alpha1);
  d["alpha2"] = est(f.alpha2);
  d["v_s"] = est(f.v_s);
  d["points"] = f.points;
  d["rms_residual"] = f.rms_residual;
  return d;
}

/// A sweep from a file (`text` empty) or from YAML/JSON text standing for the file `source` (a dict in Python).
experiments::Sweep sweepFrom(const std::string& source, const std::string& text) {
  return text.empty() ? experiments::loadSweep(source) : experiments::loadSweepText(text, source);
}

py::dict batchResult(const experiments::BatchResult& r) {
  py::list records;
  for (const auto& x : r.records) {
    py::dict d;
    d["run"] = x.run;
    d["status"] = x.status;
    d["output_dir"] = x.output_dir;
    d["overrides"] = x.overrides;
    d["wall_time_s"] = x.wall_time_s;
    d["sim_time_s"] = x.sim_time_s;
    d["real_time_factor"] = x.real_time_factor;
    d["fault_type"] = x.fault_type;
    d["fault_joint"] = x.fault_joint;
    d["fault_severity"] = x.fault_severity;
    d["fault_onset_s"] = x.fault_onset_s;
    d["design"] = x.design;
    d["seed"] = x.seed;
    d["skipped"] = x.skipped;
    records.append(d);
  }
  py::dict d;
  d["manifest_path"] = r.manifest_path;
  d["ok"] = r.ok;
  d["failed"] = r.failed;
  d["skipped"] = r.skipped;
  d["wall_time_s"] = r.wall_time_s;
  d["records"] = records;
  return d;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "jointsim C++ core: the engine of the jointsim package (use the package's functions)";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      py::dict f;
      f["file"] = e.file();
      f["line"] = e.line();
      f["key_path"] = e.keyPath();
      f["reason"] = e.message();
      if (e.missingFile()) f["missing_path"] = e.missingPath();
      raisePython(e.missingFile() ? "InputFileNotFoundError" : "InputError", PyExc_ValueError, e.what(), f);
    } catch (const UnidentifiableError& e) {
      raisePython("UnidentifiableError", PyExc_ValueError, e.what(), py::dict());
    } catch (const SolverError& e) {
      py::dict f;
      f["time"] = e.time();
      f["flag"] = e.flag();
      f["component"] = e.component();
      raisePython("SolverError", PyExc_RuntimeError, e.what(), f);
    } catch (const ConcurrentUse& e) {
      raisePython("ConcurrentUseError", PyExc_RuntimeError, e.what(), py::dict());
    } catch (const Error& e) {
      PyErr_SetString(PyExc_RuntimeError, e.what());
    } catch (const py::cast_error& e) {
      PyErr_SetString(PyExc_TypeError, e.what());
    }
  });
  m.attr("__version__") = version();
  g_main_thread = py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();

  // ------------------------------------------------------------------------------------------ multibody
  py::class_<PyModel, std::shared_ptr<PyModel>>(m, "Model",
                                                "A robot's rigid-body model with its own workspace (load_robot).")
      .def_property_readonly(
          "name", [](const PyModel& p) { return p.model.name; }, "Name of the robot (from its file).")
      .def_property_readonly(
          "nq", [](const PyModel& p) { return p.model.nq; }, "Number of joints (= of generalised coordinates).")
      .def_property_readonly(
          "joint_names", [](const PyModel& p) { return p.model.joint_names; },
          "Names of the movable joints, base to tip (the order of q).")
      .def_property_readonly("frame_names", &PyModel::frameNames,
                             "Names of the frames (bodies, joints, tool) for frame_placement/frame_jacobian.")
      .def_property_readonly(
          "tip_frame", [](const PyModel& p) { return p.model.tip_frame; },
          "The default frame of frame_placement/frame_jacobian: the last link of the chain (or the tool frame).")
      .def_property_readonly(
          "gravity", [](const PyModel& p) { return Eigen::VectorXd(p.model.gravity); },
          "Gravity acceleration in the base frame [m/s^2], shape (3,).")
      .def("__repr__", [](const PyModel& p) {
        return "<jointsim.Model '" + p.model.name + "' with " + std::to_string(p.model.nq) + " joints>";
      });
  m.def(
      "load_robot", [](const std::string& path) { return std::make_shared<PyModel>(multibody::loadRobot(path)); },
      py::arg("path"));
  m.def(
      "rnea",
      [](PyModel& p, const Array& q, const Array& qd, const Array& qdd) {
        const Use use(p.gate, "Model");
        return perState3(p, q, qd, qdd, "q", "qd", "qdd", [&p](const auto& a, const auto& b, const auto& c) {
          return multibody::rnea(p.model, p.data, a, b, c);
        });
      },
      py::arg("model"), py::arg("q"), py::arg("qd"), py::arg("qdd"));
  m.def(
      "aba",
      [](PyModel& p, const Array& q, const Array& qd, const Array& tau) {
        const Use use(p.gate, "Model");
        return perState3(p, q, qd, tau, "q", "qd", "tau", [&p](const auto& a, const auto& b, const auto& c) {
          return multibody::aba(p.model, p.data, a, b, c);
        });
      },
      py::arg("model"), py::arg("q"), py::arg("qd"), py::arg("tau"));
  m.def(
      "gravity_torques",
      [](PyModel& p, const Array& q) {
        const Use use(p.gate, "Model");
        return perState3(p, q, q, q, "q", "q", "q", [&p](const auto& a, const auto&, const auto&) {
          return multibody::gravityTorques(p.model, p.data, a);
        });
      },
      py::arg("model"), py::arg("q"));
  m.def(
      "crba",
      [](PyModel& p, const Array& q) {
        const Use use(p.gate, "Model");
        const auto n = p.model.nq;
        const States Q = states(q, n, "q");
        if (!Q.batch) return toArray(Eigen::MatrixXd(multibody::crba(p.model, p.data, row(Q, 0, n))));
        py::array_t<double> out({Q.rows, static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(n)});
        double* o = out.mutable_data();
        {
          py::gil_scoped_release release;
          for (py::ssize_t i = 0; i < Q.rows; ++i) {
            const Eigen::MatrixXd& M = multibody::crba(p.model, p.data, row(Q, i, n));
            Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(o + i * n * n, n, n) = M;
          }
        }
        return out;
      },
      py::arg("model"), py::arg("q"));
  m.def(
      "rnea_derivatives",
      [](PyModel& p, const Array& q, const Array& qd, const Array& qdd) {
        const Use use(p.gate, "Model");
        const auto n = p.model.nq;
        multibody::computeRneaDerivatives(p.model, p.data, vec(q, n, "q"), vec(qd, n, "qd"), vec(qdd, n, "qdd"));
        return py::make_tuple(toArray(p.data.dtau_dq), toArray(p.data.dtau_dqd), toArray(p.data.M));
      },
      py::arg("model"), py::arg("q"), py::arg("qd"), py::arg("qdd"));
  m.def(
      "aba_derivatives",
      [](PyModel& p, const Array& q, const Array& qd, const Array& tau) {
        const Use use(p.gate, "Model");
        const auto n = p.model.nq;
        multibody::computeAbaDerivatives(p.model, p.data, vec(q, n, "q"), vec(qd, n, "qd"), vec(tau, n, "tau"));
        return py::make_tuple(toArray(p.data.ddq_dq), toArray(p.data.ddq_dqd), toArray(p.data.Minv));
      },
      py::arg("model"), py::arg("q"), py::arg("qd"), py::arg("tau"));
  m.def(
      "frame_placement",
      [](PyModel& p, const Array& q, const py::object& frame) {
        const Use use(p.gate, "Model");
        const int f = frameOf(p.model, frame);
        multibody::forwardKinematics(p.model, p.data, vec(q, p.model.nq, "q"));
        const auto& X = p.data.oMf[static_cast<size_t>(f)];
        Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
        T.topLeftCorner<3, 3>() = X.R;
        T.topRightCorner<3, 1>() = X.p;
        return toArray(Eigen::MatrixXd(T));
      },
      py::arg("model"), py::arg("q"), py::arg("frame") = py::none());
  m.def(
      "frame_jacobian",
      [](PyModel& p, const Array& q, const py::object& frame) {
        const Use use(p.gate, "Model");
        const int f = frameOf(p.model, frame);
        return toArray(Eigen::MatrixXd(multibody::frameJacobian(p.model, p.data, vec(q, p.model.nq, "q"), f)));
      },
      py::arg("model"), py::arg("q"), py::arg("frame") = py::none());

  // ------------------------------------------------------------------------------------------ experiments
  py::class_<PyExperiment>(m, "Experiment")
      .def_property_readonly("name", [](const PyExperiment& x) { return x.e->name(); })
      .def_property_readonly("type", [](const PyExperiment& x) { return x.e->type(); })
      .def_property_readonly("file", [](const PyExperiment& x) { return x.e->file(); })
      .def_property_readonly("columns", [](const PyExperiment& x) { return sim::tableColumns(x.e->plant()); });
  m.def(
      "load_experiment",
      [](const std::string& path, const std::vector<std::string>& overrides) {
        return PyExperiment{std::shared_ptr<experiments::Experiment>(experiments::loadExperiment(path, overrides))};
      },
      py::arg("path"), py::arg("overrides") = std::vector<std::string>{});
  m.def(
      "run_in_memory",
      [](PyExperiment& x) {
        const Use use(x.gate, "Experiment");
        const experiments::ExperimentResult r = interruptible([&] { return experiments::runInMemory(*x.e); });
        py::dict out;
        out["columns"] = r.log.columns;
        out["values"] = toArray(r.log.values);
        py::dict extras;
        for (const auto& t : r.extras)
          extras[py::str(t.suffix)] = py::make_tuple(t.table.columns, toArray(t.table.values));
        out["extras"] = extras;
        out["summary_json"] = r.summary_json;
        return out;
      },
      py::arg("experiment"));
  m.def(
      "run_experiment_file",
      [](const std::string& path, const std::string& output_dir, const std::vector<std::string>& overrides) {
        experiments::RunOptions o;
        o.output_dir = output_dir;
        o.overrides = overrides;
        const experiments::RunReport r = interruptible([&] { return experiments::runExperimentFile(path, o); });
        py::dict d;
        d["status"] = r.status;
        d["csv_path"] = r.csv_path;
        d["summary_path"] = r.summary_path;
        d["sim_time_s"] = r.sim_time_s;
        d["wall_time_s"] = r.wall_time_s;
        d["real_time_factor"] = r.real_time_factor;
        d["warnings"] = r.warnings;
        return d;
      },
      py::arg("path"), py::arg("output_dir") = "", py::arg("overrides") = std::vector<std::string>{});

  m.def(
      "validate_file",
      [](const std::string& path, const std::vector<std::string>& overrides) {
        const experiments::ValidationReport r =
            interruptible([&] { return experiments::validateFile(path, overrides); });
        py::dict d;
        d["kind"] = r.kind;
        d["name"] = r.name;
        d["type"] = r.type;
        d["runs"] = r.runs;
        d["states"] = r.states;
        d["signals"] = r.signals;
        d["duration"] = r.duration;
        d["files"] = r.files;
        return d;
      },
      py::arg("path"), py::arg("overrides") = std::vector<std::string>{});

  // ------------------------------------------------------------------------------------------ sweeps
  m.def(
      "run_batch",
      [](const std::string& source, const std::string& text, const std::string& output_dir, int jobs, int shard_index,
         int shard_count, bool collect) {
        const experiments::Sweep sweep = sweepFrom(source, text);
        experiments::BatchOptions o;
        o.output_dir = output_dir;
        o.jobs = jobs;
        o.shard_index = shard_index;
        o.shard_count = shard_count;
        const experiments::BatchResult r = interruptible(
            [&] { return collect ? experiments::collectBatch(sweep, o) : experiments::runBatch(sweep, o); });
        return batchResult(r);
      },
      py::arg("source"), py::arg("text"), py::arg("output_dir") = "", py::arg("jobs") = 1, py::arg("shard_index") = 0,
      py::arg("shard_count") = 1, py::arg("collect") = false);

  m.def(
      "write_dataset",
      [](const std::string& source, const std::string& text, const std::string& path, const std::string& output_dir) {
        const experiments::Sweep sweep = sweepFrom(source, text);
        const report::DatasetSummary r = interruptible([&] { return report::writeDataset(sweep, output_dir, path); });
        py::dict d;
        d["path"] = r.path;
        d["runs"] = r.runs;
        d["runs_with_data"] = r.runs_with_data;
        d["samples"] = r.samples;
        return d;
      },
      py::arg("source"), py::arg("text"), py::arg("path"), py::arg("output_dir") = "");

  m.def(
      "view_html",
      [](const std::string& dir, int columns, int frames, const std::string& title, long mesh_bytes) {
        report::ViewOptions o;
        o.columns = columns;
        o.frames = frames;
        o.title = title;
        o.mesh_bytes = mesh_bytes;
        return interruptible([&] { return report::viewHtml(dir, o); });
      },
      py::arg("dir"), py::arg("columns") = 1000, py::arg("frames") = 20000, py::arg("title") = "",
      py::arg("mesh_bytes") = 50'000'000L);

  // ------------------------------------------------------------------------------------------ FMU export
  m.def(
      "export_fmu",
      [](const std::string& config, const std::string& fmu_path, const std::vector<std::string>& inputs,
         const std::vector<std::string>& outputs, const std::vector<std::string>& overrides,
         const std::string& binary_dir, double step_size) {
        fmi::ExportOptions o;
        o.inputs = inputs;
        o.outputs = outputs;
        o.overrides = overrides;
        o.binary_dir = binary_dir;
        o.step_size = step_size;
        const fmi::FmuDescription d = interruptible([&] { return fmi::exportFmu(config, fmu_path, o); });
        return d.toJson().dump();
      },
      py::arg("config"), py::arg("fmu_path"), py::arg("inputs"), py::arg("outputs"), py::arg("overrides"),
      py::arg("binary_dir"), py::arg("step_size"));

  // ------------------------------------------------------------------------------------------ simulator
  py::class_<PySnapshot>(m, "Snapshot")
      .def_property_readonly("time", [](const PySnapshot& p) { return p.time; })
      .def("to_bytes", [](PySnapshot& p) { return py::bytes(p.toBytes()); })
      .def_static(
          "from_bytes",
          [](const py::bytes& b, double time) {
            PySnapshot p;
            p.bytes = std::string(b);
            p.time = time;
            return p;
          },
          py::arg("data"), py::arg("time"));
  py::class_<PySimulator>(m, "Simulator")
      .def_static(
          "from_experiment",
          [](PyExperiment& x) {
            const Use use(x.gate, "Experiment");
            PySimulator s;
            s.sim = experiments::makeSimulator(x.e);
            s.plant = s.sim->sharedPlant();  // keeps the experiment alive; only read: the simulator has its own lock
            s.robot_ptr = x.e->robotSystem();
            return s;
          },
          py::arg("experiment"))
      .def_static(
          "from_robot",
          [](const std::string& path, const py::object& q0, double rtol, double atol, int max_order, double max_step,
             double max_gamma_change, const std::string& method, double step, const py::object& jacobian_every,
             const std::string& oscillations) {
            auto robot = std::make_shared<systems::RobotSystem>(systems::loadRobotWithDrives(path));
            if (!q0.is_none()) robot->setInitialPositions(Eigen::VectorXd(vec(q0.cast<Array>(), robot->dof(), "q0")));
            PySimulator s;
            s.plant = robot;
            s.robot_ptr = robot.get();
            s.sim =
                std::make_unique<sim::Simulator>(s.plant, solverFrom(rtol, atol, max_order, max_step, max_gamma_change,
                                                                     method, step, jacobian_every, oscillations));
            return s;
          },
          py::arg("path"), py::arg("q0") = py::none(), py::arg("rtol") = 1e-6, py::arg("atol") = 1e-9,
          py::arg("max_order") = 2, py::arg("max_step") = 0.0, py::arg("max_gamma_change") = 0.3,
          py::arg("method") = "bdf", py::arg("step") = 0.0, py::arg("jacobian_every") = 1,
          py::arg("oscillations") = "damp")
      .def_property_readonly("name",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               return s.plant->name();
                             })
      .def_property_readonly("time",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               return s.sim->time();
                             })
      .def_property_readonly("state",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               return toArray(s.sim->state());
                             })
      .def(
          "set_state",
          [](PySimulator& s, const Array& y) {
            const Use use(s.gate, "Simulator");
            s.sim->setState(vec(y, s.plant->stateSize(), "state"));
          },
          py::arg("y"))
      .def(
          "state_name",
          [](PySimulator& s, int i) {
            const Use use(s.gate, "Simulator");
            return s.plant->stateName(i);
          },
          py::arg("i"))
      .def(
          "reset",
          [](PySimulator& s, const py::object& q0, const py::object& qd0) {
            const Use use(s.gate, "Simulator");
            if (q0.is_none() && qd0.is_none()) {
              s.sim->reset();
              return;
            }
            const auto& robot = s.robot();  // joint positions and rates: a robot with drives
            const int n = robot.dof();
            Eigen::VectorXd y = robot.initialState(q0.is_none() ? Eigen::VectorXd(s.plant->initialState().head(n))
                                                                : vec(q0.cast<Array>(), n, "q0"));
            if (!qd0.is_none()) y.segment(n, n) = vec(qd0.cast<Array>(), n, "qd0");
            s.sim->reset(0.0, y);
          },
          py::arg("q0") = py::none(), py::arg("qd0") = py::none())
      .def_property_readonly("state_names",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               std::vector<std::string> names;
                               for (int i = 0; i < s.plant->stateSize(); ++i) names.push_back(s.plant->stateName(i));
                               return names;
                             })
      .def("snapshot",
           [](PySimulator& s) {
             const Use use(s.gate, "Simulator");
             PySnapshot p;
             p.snapshot = std::make_shared<const sim::Snapshot>(s.sim->snapshot());
             p.plant = s.plant;
             p.time = p.snapshot->time();
             return p;
           })
      .def(
          "restore",
          [](PySimulator& s, PySnapshot& p) {
            const Use use(s.gate, "Simulator");
            if (p.snapshot && p.plant == s.plant)
              s.sim->restore(*p.snapshot);
            else
              s.sim->loadState(p.toBytes());  // another plant object of the same configuration, or unpickled
          },
          py::arg("snapshot"))
      .def("save_state",
           [](PySimulator& s) {
             const Use use(s.gate, "Simulator");
             return py::bytes(s.sim->saveState());
           })
      .def(
          "load_state",
          [](PySimulator& s, const py::bytes& b) {
            const Use use(s.gate, "Simulator");
            s.sim->loadState(std::string(b));
          },
          py::arg("data"))
      .def("copy",
           [](PySimulator& s) {
             const Use use(s.gate, "Simulator");
             PySimulator c;
             c.plant = s.plant;
             c.robot_ptr = s.robot_ptr;
             c.sim = std::make_unique<sim::Simulator>(*s.sim);
             return c;
           })
      .def(
          "advance",
          [](PySimulator& s, double dt) {
            const Use use(s.gate, "Simulator");
            return interruptible([&] { return s.sim->advance(dt); });
          },
          py::arg("dt"))
      .def(
          "advance_to",
          [](PySimulator& s, double t) {
            const Use use(s.gate, "Simulator");
            return interruptible([&] { return s.sim->advanceTo(t); });
          },
          py::arg("t"))
      .def(
          "set_limits",
          [](PySimulator& s, long max_steps, double max_wall_time, double max_state) {
            const Use use(s.gate, "Simulator");
            sim::AdvanceLimits l;
            l.max_steps = max_steps;
            l.max_wall_time = max_wall_time;
            l.max_state = max_state;
            s.sim->setLimits(l);
          },
          py::arg("max_steps"), py::arg("max_wall_time"), py::arg("max_state"))
      .def("limits",
           [](PySimulator& s) {
             const Use use(s.gate, "Simulator");
             const sim::AdvanceLimits& l = s.sim->limits();
             return py::make_tuple(l.max_steps, l.max_wall_time, l.max_state);
           })
      .def_property_readonly("signal_names",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               return s.sim->signalNames();
                             })
      .def("signal_values",
           [](PySimulator& s) {
             const Use use(s.gate, "Simulator");
             return toArray(s.sim->signals());
           })
      .def(
          "signal",
          [](PySimulator& s, const std::string& name) {
            const Use use(s.gate, "Simulator");
            return s.sim->signal(name);
          },
          py::arg("name"))
      .def(
          "signal_index",
          [](PySimulator& s, const std::string& name) {
            const Use use(s.gate, "Simulator");
            return s.sim->signalIndex(name);
          },
          py::arg("name"))
      .def_property_readonly("restarts",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               return s.sim->restarts();
                             })
      .def_property_readonly("steps",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               return s.sim->stats().steps;
                             })
      .def_property_readonly("solver_stats_json",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               nlohmann::ordered_json j;
                               experiments::solverStatsJson(j, s.sim->stats());  // the run summary's solver_stats
                               return j.dump();
                             })
      .def_property_readonly("period_wall_times",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               const sim::PeriodWallTimes w = s.sim->periodWallTimes();
                               py::dict d;
                               d["periods"] = w.periods;
                               d["p50"] = w.p50_s;
                               d["p99"] = w.p99_s;
                               d["max"] = w.max_s;
                               return d;
                             })
      .def_property_readonly("dof",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               return s.robot().dof();
                             })
      .def_property_readonly("joint_names",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               return s.robot().model().joint_names;
                             })
      .def_property_readonly("joint_positions",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               return toArray(Eigen::VectorXd(s.sim->state().head(s.robot().dof())));
                             })
      .def_property_readonly("joint_velocities",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               const int n = s.robot().dof();
                               return toArray(Eigen::VectorXd(s.sim->state().segment(n, n)));
                             })
      .def_property_readonly("gear_ratios",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               const int n = s.robot().dof();
                               Eigen::VectorXd r(n);
                               for (int k = 0; k < n; ++k) r[k] = s.robot().layout(k).ratio;
                               return toArray(r);
                             })
      .def_property_readonly("motor_velocities",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               const int n = s.robot().dof();
                               Eigen::VectorXd v(n);
                               for (int k = 0; k < n; ++k) v[k] = s.robot().motorVelocity(s.sim->state(), k);
                               return toArray(v);
                             })
      .def("model",
           [](PySimulator& s) {
             const Use use(s.gate, "Simulator");
             return std::make_shared<PyModel>(s.robot().model());
           })
      .def(
          "set_port",
          [](PySimulator& s, const py::object& j, const std::string& port) {
            const Use use(s.gate, "Simulator");
            s.robot().setCommandPort(s.state(), s.joint(j), systems::parsePort(port));
          },
          py::arg("joint"), py::arg("port"))
      .def(
          "port",
          [](PySimulator& s, const py::object& j) {
            const Use use(s.gate, "Simulator");
            return std::string(systems::portName(s.robot().commandPort(s.state(), s.joint(j))));
          },
          py::arg("joint"))
      .def_property_readonly("inputs",
                             [](PySimulator& s) {
                               const Use use(s.gate, "Simulator");
                               py::list out;
                               const auto ports = s.plant->inputPorts();
                               for (size_t i = 0; i < ports.size(); ++i) {
                                 const sim::InputPort& p = ports[i];
                                 py::dict d;
                                 d["name"] = p.name;
                                 d["unit"] = p.unit;
                                 d["min"] = p.min;
                                 d["max"] = p.max;
                                 d["description"] = p.description;
                                 d["group"] = p.group;
                                 d["mode"] = p.mode;
                                 d["active"] = s.plant->inputActive(s.state(), static_cast<int>(i));
                                 d["value"] = s.plant->input(s.state(), static_cast<int>(i));
                                 out.append(d);
                               }
                               return out;
                             })
      .def(
          "drive_parameters",
          [](PySimulator& s, const py::object& j) {
            const Use use(s.gate, "Simulator");
            const systems::DriveSpec& d = s.robot().drives()[static_cast<size_t>(s.joint(j))];
            py::dict out;
            for (const std::string& component : systems::driveComponents()) {
              py::list rows;
              for (const drive::ParameterInfo& p : systems::driveParameterTable(d, component)) {
                py::dict r;
                r["key"] = p.key;
                r["unit"] = p.unit;
                r["value"] = p.value;
                r["min"] = p.range.min;
                r["max"] = p.range.max;
                r["min_open"] = p.range.min_open;
                r["max_open"] = p.range.max_open;
                r["role"] = drive::roleName(p.role);
                r["description"] = p.description;
                rows.append(r);
              }
              out[py::str(component)] = rows;
            }
            return out;
          },
          py::arg("joint"))
      .def(
          "set_input",
          [](PySimulator& s, const std::string& name, double value) {
            const Use use(s.gate, "Simulator");
            s.plant->setInput(s.state(), sim::inputIndex(*s.plant, name), value);
          },
          py::arg("name"), py::arg("value"))
      .def(
          "release_input",
          [](PySimulator& s, const std::string& name) {
            const Use use(s.gate, "Simulator");
            s.plant->releaseInput(s.state(), sim::inputIndex(*s.plant, name));
          },
          py::arg("name"))
      .def(
          "input",
          [](PySimulator& s, const std::string& name) {
            const Use use(s.gate, "Simulator");
            return s.plant->input(s.state(), sim::inputIndex(*s.plant, name));
          },
          py::arg("name"))
      .def(
          "set_command",
          [](PySimulator& s, const py::object& j, double value) {
            const Use use(s.gate, "Simulator");
            if (!s.robot_ptr) {  // a plant without joints (a joint rig): its `command` input
              s.plant->setInput(s.state(), sim::inputIndex(*s.plant, "command"), value);
              return;
            }
            s.robot().setCommand(s.state(), s.joint(j), value);
          },
          py::arg("joint"), py::arg("value"))
      .def(
          "set_commands",
          [](PySimulator& s, const Array& v) {
            const Use use(s.gate, "Simulator");
            s.robot().setCommands(s.state(), vec(v, s.robot().dof(), "commands"));
          },
          py::arg("values"))
      .def(
          "set_setpoint",
          [](PySimulator& s, const py::object& j, double q, double qd, double qdd) {
            const Use use(s.gate, "Simulator");
            s.robot().setSetpoint(s.state(), s.joint(j), q, qd, qdd);
          },
          py::arg("joint"), py::arg("q"), py::arg("qd"), py::arg("qdd"))
      .def(
          "hold_setpoints",
          [](PySimulator& s, const Array& q, const py::object& qd, const py::object& qdd) {
            const Use use(s.gate, "Simulator");
            const int n = s.robot().dof();
            const Eigen::VectorXd qv = vec(q, n, "q");
            const Eigen::VectorXd qdv =
                qd.is_none() ? Eigen::VectorXd() : Eigen::VectorXd(vec(qd.cast<Array>(), n, "qd"));
            const Eigen::VectorXd qddv =
                qdd.is_none() ? Eigen::VectorXd() : Eigen::VectorXd(vec(qdd.cast<Array>(), n, "qdd"));
            s.robot().holdSetpoints(s.state(), qv, qdv, qddv);
          },
          py::arg("q"), py::arg("qd"), py::arg("qdd"))
      .def("release_setpoints",
           [](PySimulator& s) {
             const Use use(s.gate, "Simulator");
             s.robot().releaseSetpoints(s.state());
           })
      .def(
          "set_external_wrench",
          [](PySimulator& s, const std::string& frame, const Array& w) {
            const Use use(s.gate, "Simulator");
            s.robot().setExternalWrench(s.state(), frame, Eigen::Matrix<double, 6, 1>(vec(w, 6, "wrench")));
          },
          py::arg("frame"), py::arg("wrench"));

  // ------------------------------------------------------------------------------------------ agreement
  m.def(
      "read_csv",
      [](const std::string& path) {
        const io::CsvTable t = io::readCsv(path);
        return py::make_tuple(t.header, Eigen::MatrixXd(t.data));
      },
      py::arg("path"));
  m.def(
      "agreement",
      [](const std::vector<std::string>& ph, const Eigen::MatrixXd& pv, const std::string& pname,
         const std::vector<std::string>& mh, const Eigen::MatrixXd& mv, const std::string& mname,
         const std::vector<std::pair<std::string, std::string>>& pairs, double time_offset, double max_lag,
         double t_begin, double t_end) {
        auto table = [](const std::vector<std::string>& h, const Eigen::MatrixXd& v, const std::string& name) {
          if (static_cast<Eigen::Index>(h.size()) != v.cols())
            throw InputError(name + ": " + std::to_string(h.size()) + " column names for " + std::to_string(v.cols()) +
                             " columns");
          if (!v.allFinite()) throw InputError(name + ": every value must be finite");
          io::CsvTable t;
          t.path = name;
          t.header = h;
          t.data = v;
          for (Eigen::Index r = 0; r < v.rows(); ++r) t.lines.push_back(static_cast<int>(r) + 2);
          return t;
        };
        std::vector<report::SignalPair> sp;
        for (const auto& [a, b] : pairs) sp.push_back({a, b});
        report::AgreementOptions o;
        o.time_offset = time_offset;
        o.max_lag = max_lag;
        o.t_begin = t_begin;
        o.t_end = t_end;
        return report::agreementJson(report::agreement(table(ph, pv, pname), table(mh, mv, mname), sp, o));
      },
      py::arg("predicted_header"), py::arg("predicted_values"), py::arg("predicted_name"), py::arg("measured_header"),
      py::arg("measured_values"), py::arg("measured_name"), py::arg("pairs"), py::arg("time_offset"),
      py::arg("max_lag"), py::arg("t_begin"), py::arg("t_end"));

  // ------------------------------------------------------------------------------------------ identification
  m.def(
      "identify_currents",
      [](const std::string& robot, const std::string& log, const std::string& output, const std::string& time,
         const std::string& q, const std::string& qd, const std::string& qdd, const std::string& current, bool ur_rtde,
         double t_begin, double t_end, double min_speed, double scale_bound, bool fit_offset, const std::string& refine,
         const std::vector<std::string>& refine_set, int refine_iterations) {
        identify::CurrentLogColumns c{time, q, qd, qdd, current};
        if (ur_rtde) {
          c = identify::CurrentLogColumns::urRtde();
          if (!time.empty()) c.time = time;
        }
        identify::DriveCalibrationOptions o;
        o.t_begin = t_begin;
        o.t_end = t_end;
        o.fit.min_speed = min_speed;
        o.fit.scale_bound = scale_bound;
        o.fit.fit_offset = fit_offset;
        o.refine_experiment = refine;
        o.refine_overrides = refine_set;
        o.refine_iterations = refine_iterations;
        const identify::DriveCalibration cal = interruptible([&] {
          return identify::calibrateDrives(robot, log, c, o, output.empty() ? std::string("drives.yaml") : output);
        });
        if (!output.empty()) io::writeFileAtomically(output, cal.drives_yaml);
        return py::make_tuple(identify::calibrationJson(cal), cal.drives_yaml);
      },
      py::arg("robot"), py::arg("log"), py::arg("output"), py::arg("time"), py::arg("q"), py::arg("qd"), py::arg("qdd"),
      py::arg("current"), py::arg("ur_rtde"), py::arg("t_begin"), py::arg("t_end"), py::arg("min_speed"),
      py::arg("scale_bound"), py::arg("fit_offset"), py::arg("refine"), py::arg("refine_set"),
      py::arg("refine_iterations"));
  m.def(
      "identify_clamping",
      [](const Array& t, const Array& angle, const Array& torque, const py::object& fixed_backlash) {
        identify::ClampingData d;
        d.source = "python arrays";
        d.time = anyVec(t, "time");
        d.angle = anyVec(angle, "angle");
        d.torque = anyVec(torque, "torque");
        identify::ClampingFitOptions o;
        if (!fixed_backlash.is_none()) o.fixed_backlash = fixed_backlash.cast<double>();
        const identify::ClampingFitResult r = interruptible([&] { return identify::identifyClamping(d, o); });
        py::dict out;
        out["stiffness"] = fitted(r.stiffness);
        out["backlash"] = fitted(r.backlash);
        out["friction"] = fitted(r.friction);
        out["center"] = fitted(r.center);
        out["rms_residual"] = r.rms_residual;
        out["points"] = r.points;
        return out;
      },
      py::arg("time"), py::arg("angle"), py::arg("torque"), py::arg("fixed_backlash") = py::none());
  m.def(
      "fit_friction_map",
      [](const Array& v, const Array& tau) {
        const Eigen::VectorXd vv = anyVec(v, "velocity"), tt = anyVec(tau, "torque");
        if (vv.size() != tt.size())
          throw InputError("fit_friction_map: velocity and torque have " + std::to_string(vv.size()) + " and " +
                           std::to_string(tt.size()) + " entries");
        const identify::FrictionFit f = interruptible([&] {
          return identify::fitFrictionMap(std::vector<double>(vv.data(), vv.data() + vv.size()),
                                          std::vector<double>(tt.data(), tt.data() + tt.size()));
        });
        py::dict out;
        out["positive"] = direction(f.positive);
        out["negative"] = direction(f.negative);
        out["delta"] = f.delta.value;
        return out;
      },
      py::arg("velocity"), py::arg("torque"));
}
