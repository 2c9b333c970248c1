// A new experiment type is one source file and one row: this file defines a mass–spring–damper plant, its
// Experiment and its loader, registers the type, and runs it through the experiment-file entry point (CSV and
// summary.json written) and through the plant seam (sim::simulate), both against the closed-form step response.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/experiments/registry.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "test_util.hpp"

using namespace jointsim;
using ::testing::HasSubstr;

namespace {

/// m ẍ + c ẋ + k x = F for t >= t_step (0 before); state [x, ẋ]; signals x [m], v [m/s], spring force [N].
class MassSpringDamper : public sim::Plant {
 public:
  MassSpringDamper(double m, double c, double k, double force, double t_step)
      : m_(m), c_(c), k_(k), F_(force), t_step_(t_step) {}
  std::string name() const override { return "mass-spring-damper"; }
  int stateSize() const override { return 2; }
  Eigen::VectorXd initialState() const override { return Eigen::Vector2d::Zero(); }
  void derivatives(const sim::PlantState&, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> yd) const override {
    yd[0] = y[1];
    yd[1] = (force(t) - c_ * y[1] - k_ * y[0]) / m_;
  }
  std::vector<double> timeEvents(double) const override { return {t_step_}; }
  const std::vector<std::string>& signalNames() const override { return names_; }
  void signals(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override {
    out << y[0], y[1], k_ * y[0];
  }
  /// Closed form: underdamped step response x(t) = F/k (1 − e^{−ζω τ} (cos ω_d τ + ζω/ω_d sin ω_d τ)), τ = t − t_step.
  double exact(double t) const {
    if (t < t_step_) return 0.0;
    const double w = std::sqrt(k_ / m_), z = c_ / (2 * std::sqrt(k_ * m_)), wd = w * std::sqrt(1 - z * z),
                 tau = t - t_step_;
    return F_ / k_ * (1 - std::exp(-z * w * tau) * (std::cos(wd * tau) + z * w / wd * std::sin(wd * tau)));
  }

 private:
  double force(double t) const { return t >= t_step_ ? F_ : 0.0; }
  double m_, c_, k_, F_, t_step_;
  std::vector<std::string> names_{"x[m]", "v[m/s]", "spring_force[N]"};
};

class MsdExperiment : public experiments::Experiment {
 public:
  MsdExperiment(MassSpringDamper plant, double duration, double log_rate, sim::CvodeOptions solver)
      : plant_(std::move(plant)), duration_(duration), log_rate_(log_rate), solver_(solver) {}
  sim::Plant& plant() override { return plant_; }
  sim::SimulateOptions simulateOptions() const override {
    sim::SimulateOptions o;
    o.t_end = duration_;
    o.output_rate = log_rate_;
    o.solver = solver_;
    return o;
  }
  void describe(nlohmann::ordered_json& p, const sim::SimulationResult& r) const override {
    p["duration"] = duration_;
    p["events"] = r.events;
  }
  const MassSpringDamper& msd() const { return plant_; }

 private:
  MassSpringDamper plant_;
  double duration_, log_rate_;
  sim::CvodeOptions solver_;
};

// The row of the registry.
experiments::ExperimentType msdType() {
  experiments::ExperimentType t;
  t.name = "mass_spring_damper";
  t.description = "a mass on a spring and damper under a force step (test type)";
  t.load = [](const io::YamlValue& root, const experiments::LoadContext&) -> std::unique_ptr<experiments::Experiment> {
    root.allowKeys(
        {"experiment", "mass", "stiffness", "damping", "force", "step_time", "duration", "log_rate", "solver"});
    const double m = root.required("mass", "mass in kg").asDouble("a mass in kg");
    if (!(m > 0)) root["mass"].failExpected("a mass > 0 kg");
    double duration = 0, log_rate = 100;
    experiments::readDurationAndLogRate(root, duration, log_rate);
    sim::CvodeOptions solver;
    solver.rtol = 1e-10;
    solver.atol = 1e-12;
    solver = experiments::readSolver(root["solver"], solver);
    MassSpringDamper plant(m, root["damping"].asDouble(0.0, "N·s/m"), root.required("stiffness", "N/m").asDouble("N/m"),
                           root.required("force", "N").asDouble("N"), root["step_time"].asDouble(0.0, "s"));
    return std::make_unique<MsdExperiment>(plant, duration, log_rate, solver);
  };
  return t;
}

std::string writeExperiment(const std::filesystem::path& dir, const std::string& extra = "") {
  std::filesystem::create_directories(dir);
  const auto p = dir / "msd.yaml";
  std::ofstream(p) << "experiment: {name: msd, type: mass_spring_damper}\nmass: 2.0\nstiffness: 800.0\ndamping: 4.0\n"
                      "force: 10.0\nstep_time: 0.05\nduration: 0.5\nlog_rate: 1000\n"
                   << extra;
  return p.string();
}

}  // namespace

TEST(ExperimentRegistry, ANewTypeRunsThroughTheFileEntryPointAndThePlantSeam) {
  if (!experiments::findExperimentType("mass_spring_damper")) experiments::registerExperimentType(msdType());
  EXPECT_THAT(experiments::experimentTypeNames(), HasSubstr("mass_spring_damper"));
  const test::TempDir tmp;
  const auto dir = tmp / "jointsim_registry_msd";
  const std::string file = writeExperiment(dir);

  // Experiment-file entry point: CSV and summary.json written.
  experiments::RunOptions o;
  o.output_dir = (dir / "out").string();
  const experiments::RunReport r = experiments::runExperimentFile(file, o);
  EXPECT_EQ(r.status, "ok");
  const io::CsvTable log = io::readCsv(r.csv_path);
  ASSERT_EQ(log.header, (std::vector<std::string>{"time[s]", "x[m]", "v[m/s]", "spring_force[N]"}));
  ASSERT_EQ(log.rows(), 501);
  const MassSpringDamper ref(2.0, 4.0, 800.0, 10.0, 0.05);
  double worst = 0;
  for (Eigen::Index k = 0; k < log.rows(); ++k)
    worst = std::max(worst, std::abs(log.data(k, 1) - ref.exact(log.data(k, 0))));
  EXPECT_LT(worst, 1e-7) << "closed-form step response (peak x ≈ 0.02 m)";
  std::ifstream in(r.summary_path);
  const nlohmann::json summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["type"], "mass_spring_damper");
  EXPECT_EQ(summary["status"], "ok");
  EXPECT_EQ(summary["parameters"]["events"], 1) << "the force step is a time event";
  EXPECT_EQ(summary["parameters"]["config"]["mass"], 2.0);
  EXPECT_FALSE(summary["jointsim_version"].get<std::string>().empty());
  ASSERT_EQ(summary["inputs"].size(), 1u);
  EXPECT_EQ(summary["inputs"][0]["path"], std::filesystem::absolute(file).lexically_normal().string());

  // The same in memory (load, override, run): identical log, nothing written.
  auto e = experiments::loadExperiment(file, {"mass=2.0"});
  const experiments::ExperimentResult mem = experiments::runInMemory(*e);
  ASSERT_EQ(mem.log.values.rows(), log.rows());
  EXPECT_EQ((mem.log.values - log.data).cwiseAbs().maxCoeff(), 0.0) << "same numbers as the CSV (%.17g round-trips)";

  // Through the plant seam directly.
  MassSpringDamper plant(2.0, 4.0, 800.0, 10.0, 0.05);
  sim::SimulateOptions so = e->simulateOptions();
  sim::SimulationResult res;
  const sim::SignalTable t = sim::simulateTable(plant, so, &res);
  EXPECT_EQ(res.events, 1);
  EXPECT_EQ(res.outputs, 501);
  EXPECT_NEAR(t.values(t.values.rows() - 1, t.column("x")), ref.exact(0.5), 1e-7);
  EXPECT_NEAR(t.values(300, t.column("spring_force")), 800.0 * t.values(300, t.column("x[m]")), 1e-12);

  // Bad input in the new type's file: a one-line error naming the file and the key, nothing written.
  const std::string bad = writeExperiment(dir / "bad", "speed: 3\n");
  try {
    experiments::runExperimentFile(bad, o);
    ADD_FAILURE() << "unknown key accepted";
  } catch (const InputError& err) {
    EXPECT_THAT(err.what(), HasSubstr("msd.yaml:9: speed: unknown key 'speed'"));
  }
}

TEST(ExperimentRegistry, TypesAreUniqueAndTheUnknownTypeErrorListsThem) {
  if (!experiments::findExperimentType("mass_spring_damper")) experiments::registerExperimentType(msdType());
  EXPECT_THROW(experiments::registerExperimentType(msdType()), InputError);
  for (const char* t :
       {"passive_robot", "joint_rig", "tracking", "drive_chain", "robotr3_axis", "robotr3_full", "clamping"}) {
    const experiments::ExperimentType* row = experiments::findExperimentType(t);
    ASSERT_NE(row, nullptr) << t;
    EXPECT_FALSE(row->description.empty()) << t;
    EXPECT_TRUE(row->figures) << t;
  }
  const test::TempDir tmp;
  const auto& dir = tmp.path();
  std::ofstream(dir / "x.yaml") << "experiment: {name: x, type: spring_mass}\n";
  try {
    experiments::loadExperiment((dir / "x.yaml").string());
    ADD_FAILURE() << "unknown type accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("x.yaml:1: experiment.type: expected an experiment type (known: passive_robot, "));
    EXPECT_THAT(e.what(), HasSubstr("mass_spring_damper"));
  }
}
