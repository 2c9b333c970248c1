// identify::fitDriveCurrents: the torque-constant scale, friction per direction and current offset of each UR5
// joint recovered from currents synthesised along the real UR5 log's motion with known parameters, current noise
// and quantisation; the bounds; the errors.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/control/trajectory_yaml.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/identify/current_fit.hpp"
#include "jointsim/identify/drive_calibration.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/io/yaml.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

using namespace jointsim;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace {

const std::string kDir = std::string(JOINTSIM_SOURCE_DIR) + "/config/";

/// The shipped log's motion: measured q, commanded q̇ and q̈ (currents filled in by the test).
identify::CurrentLog logMotion() {
  const io::CsvTable t = io::readCsv(kDir + "logs/ur5_kufieta2013_mov6_first30s.csv");
  identify::CurrentLog log;
  log.source = "synthetic";
  const Eigen::Index K = t.rows();
  for (Eigen::MatrixXd* m : {&log.q, &log.qd, &log.qdd, &log.current}) m->resize(K, 6);
  for (int j = 0; j < 6; ++j) {
    const std::string n = std::to_string(j + 1);
    log.q.col(j) = t.data.col(t.require("q_actual_" + n, ""));
    log.qd.col(j) = t.data.col(t.require("qd_target_" + n, ""));
    log.qdd.col(j) = t.data.col(t.require("qdd_target_" + n, ""));
  }
  return log;
}

std::vector<identify::DriveNominal> ur5Drives() {  // [Raviola2023]'s motors, N = 101
  const double kt[6] = {0.1350, 0.1361, 0.1355, 0.0957, 0.0865, 0.0893};
  std::vector<identify::DriveNominal> d;
  for (int j = 0; j < 6; ++j) d.push_back({101.0, kt[j], j < 3 ? 1.877e-4 : 2.076e-5});
  return d;
}

identify::CurrentFit truth(bool with_offset) {
  const double s[6] = {0.75, 0.82, 1.25, 0.9, 1.1, 0.7};
  const double fcp[6] = {6.0, 8.0, 5.0, 1.5, 1.2, 1.0}, fcn[6] = {7.0, 6.5, 4.0, 1.8, 1.0, 1.3};
  const double fvp[6] = {10.0, 12.0, 8.0, 2.0, 2.5, 1.5}, fvn[6] = {9.0, 14.0, 6.0, 2.5, 2.0, 2.0};
  const double i0[6] = {-0.1, -0.1, -0.03, 0.14, 0.01, -0.05};
  identify::CurrentFit f;
  for (int j = 0; j < 6; ++j) {
    identify::JointCurrentFit p;
    p.kt_scale.value = s[j];
    p.coulomb_pos.value = fcp[j];
    p.coulomb_neg.value = with_offset ? fcp[j] : fcn[j];
    p.viscous_pos.value = fvp[j];
    p.viscous_neg.value = fvn[j];
    p.offset.value = with_offset ? i0[j] : 0.0;
    f.joints.push_back(p);
  }
  return f;
}

/// The full twin with the drives of `known` (k_t scales on the nominal ur5_drives.yaml, LuGre friction per
/// direction) following the Fourier excitation: its log, and the excitation trajectory itself.
struct TwinExcitation {
  sim::SignalTable log;
  std::unique_ptr<control::JointTrajectory> trajectory;
};
TwinExcitation twinExcitation(const systems::RobotSystem& nominal, const identify::CurrentFit& known) {
  std::vector<std::string> set = {"robot=" + kDir + "robots/ur5_drives_measured.yaml"};
  for (size_t k = 0; k < 6; ++k) {
    const auto& d = nominal.drives()[k];
    const auto& p = known.joints[k];
    const std::string j = "+drives." + d.joint + ".";
    auto num = [](double v) { return std::to_string(v); };
    set.push_back(j + "motor.kt=" + num(p.kt_scale.value * d.motor.kt));
    set.push_back(j + "motor.ke=" + num(p.kt_scale.value * d.motor.kt));
    set.push_back(j + "friction.positive.alpha0=" + num(p.coulomb_pos.value));
    set.push_back(j + "friction.negative.alpha0=" + num(p.coulomb_neg.value));
    set.push_back(j + "friction.positive.alpha2=" + num(p.viscous_pos.value));
    set.push_back(j + "friction.negative.alpha2=" + num(p.viscous_neg.value));
  }
  auto e = experiments::loadExperiment(kDir + "experiments/ur5_excitation.yaml", set);
  TwinExcitation out;
  out.log = experiments::runInMemory(*e).log;
  const auto root = io::YamlValue::loadFile(kDir + "experiments/ur5_excitation.yaml");
  out.trajectory = control::trajectoryFromYaml(root["trajectory"], 6, kDir + "experiments");
  return out;
}

}  // namespace

void recoverKnownParameters(bool with_offset) {
  const multibody::Model ur5 = multibody::loadRobot(kDir + "robots/ur5.yaml");
  const auto drives = ur5Drives();
  identify::CurrentLog log = logMotion();
  const identify::CurrentFit known = truth(with_offset);
  log.current = identify::predictCurrents(ur5, drives, log, known);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);  // 0.01 A noise, then 1 mA steps as a logged current has
  for (Eigen::Index k = 0; k < log.current.rows(); ++k)
    for (Eigen::Index j = 0; j < 6; ++j) log.current(k, j) = std::round((log.current(k, j) + noise(rng)) * 1e3) * 1e-3;
  identify::CurrentFitOptions o;
  o.fit_offset = with_offset;
  const identify::CurrentFit fit = identify::fitDriveCurrents(ur5, drives, log, o);
  for (int j = 0; j < 6; ++j) {
    const auto& f = fit.joints[static_cast<size_t>(j)];
    const auto& t = known.joints[static_cast<size_t>(j)];
    // Every estimate within 3 standard errors of the truth (the reported uncertainty is honest), and within 2 %
    // where the motion identifies it to 0.7 % or better (the base, shoulder and elbow; on the wrists this log's
    // motion barely separates the torque-constant scale from the friction: σ 1–3.7 %).
    auto within = [&](const identify::ParameterEstimate& a, const identify::ParameterEstimate& b, const char* what) {
      EXPECT_GT(a.std_error, 0.0) << what;
      EXPECT_LT(std::abs(a.value - b.value), 3.0 * a.std_error) << "joint " << j + 1 << " " << what;
      if (a.std_error <= 0.007 * std::abs(b.value)) {
        EXPECT_NEAR(a.value, b.value, 0.02 * std::abs(b.value)) << "joint " << j + 1 << " " << what;
      }
      if (j < 3) {
        EXPECT_LT(a.std_error, 0.007 * std::abs(b.value)) << "joint " << j + 1 << " " << what;
      }
    };
    within(f.kt_scale, t.kt_scale, "kt_scale");
    within(f.coulomb_pos, t.coulomb_pos, "coulomb_pos");
    within(f.coulomb_neg, t.coulomb_neg, "coulomb_neg");
    within(f.viscous_pos, t.viscous_pos, "viscous_pos");
    within(f.viscous_neg, t.viscous_neg, "viscous_neg");
    if (with_offset)
      EXPECT_NEAR(f.offset.value, t.offset.value, 2e-3) << "joint " << j + 1;  // 2 % of ~0.1 A
    else
      EXPECT_EQ(f.offset.value, 0.0);
    EXPECT_NEAR(f.rms, 0.01, 1.5e-3);  // the noise (and the quantisation's 0.3 mA)
    EXPECT_TRUE(f.at_bound.empty());
  }
}

TEST(CurrentFit, RecoversKnownScaleAndFrictionPerDirectionFromNoisyQuantisedCurrents) { recoverKnownParameters(false); }

TEST(CurrentFit, RecoversKnownScaleFrictionAndOffsetFromNoisyQuantisedCurrents) { recoverKnownParameters(true); }

TEST(CurrentFit, BoundsHoldAndErrorsNameTheProblem) {
  const multibody::Model ur5 = multibody::loadRobot(kDir + "robots/ur5.yaml");
  const auto drives = ur5Drives();
  identify::CurrentLog log = logMotion();
  identify::CurrentFit known = truth(false);
  known.joints[0].kt_scale.value = 0.3;  // outside ±40 %: the fit stops on the bound and says so
  log.current = identify::predictCurrents(ur5, drives, log, known);
  const identify::CurrentFit fit = identify::fitDriveCurrents(ur5, drives, log);
  EXPECT_NEAR(fit.joints[0].kt_scale.value, 0.6, 1e-9);
  EXPECT_THAT(fit.joints[0].at_bound, ::testing::Contains(std::string("kt_scale")));
  EXPECT_TRUE(fit.joints[1].at_bound.empty());

  identify::CurrentFitOptions o;
  o.min_speed = 10.0;  // no sample moves that fast
  EXPECT_THAT([&] { identify::fitDriveCurrents(ur5, drives, log, o); },
              ThrowsMessage<UnidentifiableError>(
                  HasSubstr("joint shoulder_pan_joint: 0 samples moving forward and 0 backward")));
  o = {};
  o.scale_bound = 1.5;
  EXPECT_THAT([&] { identify::fitDriveCurrents(ur5, drives, log, o); },
              ThrowsMessage<InputError>(HasSubstr("scale_bound: expected a value in (0, 1), got 1.5")));
  log.current(3, 2) = std::nan("");
  EXPECT_THAT([&] { identify::fitDriveCurrents(ur5, drives, log); },
              ThrowsMessage<InputError>(HasSubstr("synthetic: every value must be finite")));
}

TEST(CurrentCalibration, TheCommandWritesADrivesFileThatTrackingLoadsWithTheFittedValues) {
  const jointsim::test::TempDir tmp;
  const std::string out = (tmp / "drives.yaml").string(), json = (tmp / "cal.json").string();
  const auto r = jointsim::test::runCli("identify currents " + kDir + "robots/ur5_drives.yaml " + kDir +
                                        "logs/ur5_kufieta2013_mov6_first30s.csv -o " + out + " --json " + json);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("on a bound: kt_scale"));  // wrist 3 (docs/replay.md)
  // The written file is a robot-with-drives file: k_t = the nominal × s, friction per direction as fitted.
  const systems::RobotSystem nominal = systems::loadRobotWithDrives(kDir + "robots/ur5_drives.yaml");
  const systems::RobotSystem cal = systems::loadRobotWithDrives(out);
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  for (size_t k = 0; k < 6; ++k) {
    const double s = j["joints"][k]["kt_scale"]["value"].get<double>();
    EXPECT_NEAR(cal.drives()[k].motor.kt, s * nominal.drives()[k].motor.kt, 1e-7) << k;
    EXPECT_NEAR(cal.drives()[k].motor.ke, cal.drives()[k].motor.kt, 1e-12) << k;
    const auto table = systems::driveParameterTable(cal.drives()[k], "friction");
    auto value = [&](const std::string& key) { return drive::parameterValue(table, key, "friction"); };
    EXPECT_NEAR(value("positive.alpha0"), j["joints"][k]["coulomb_pos"]["value"].get<double>(), 1e-6) << k;
    EXPECT_NEAR(value("negative.alpha2"), j["joints"][k]["viscous_neg"]["value"].get<double>(), 1e-6) << k;
  }

  // A log without the current columns: one line naming the file and the column, exit 2, nothing written.
  const std::string out2 = (tmp / "none.yaml").string();
  const auto bad =
      jointsim::test::runCli("identify currents " + kDir + "robots/ur5_drives.yaml " + kDir +
                             "logs/ur5_kufieta2013_mov6_first30s.csv -o " + out2 + " --current 'amps_{j}'");
  EXPECT_EQ(bad.status, 2);
  EXPECT_THAT(bad.err, HasSubstr("ur5_kufieta2013_mov6_first30s.csv:1: missing column 'amps_1'"));
  EXPECT_FALSE(std::filesystem::exists(out2));
}

TEST(CurrentCalibration, TheInnerModelExplainsTheFullTwinsCurrentsAndItsFitIsBiasedByItsDynamics) {
  // The full twin (strain-wave gears, LuGre friction per direction, motor electrics, the cascade) with known drive
  // parameters follows the Fourier excitation; its measured joint angles (1e-6 rad steps) and motor currents (0.01 A
  // noise, 1 mA steps), with the commanded q̇, q̈ of the trajectory as a robot controller logs them, are the log.
  // 1. The inner model with the true parameters explains the twin's currents: regression slope 1 within 0.5 %
  //    (measured 0.9976 … 1.0025), RMS difference below 0.1 A (0.014 … 0.086 A: the gear's and the bristles' own
  //    dynamics and the tracking lag, which the inner model has not).
  // 2. Fitted on these currents, the inner model's estimates are biased by that unmodelled dynamics: the
  //    torque-constant scale by −1.1 % (shoulder) … −9 % (wrist 3), the friction by up to 18 % (docs/replay.md).
  //    Checked: within 10 % (s). The refinement against the full twin (the next test) removes that bias.
  const identify::CurrentFit known = truth(false);
  const systems::RobotSystem nominal = systems::loadRobotWithDrives(kDir + "robots/ur5_drives.yaml");
  std::vector<identify::DriveNominal> drives;
  for (const auto& d : nominal.drives()) drives.push_back({d.transmission->ratio(), d.motor.kt, d.motor.J_M});
  const TwinExcitation run = twinExcitation(nominal, known);
  const auto& L = run.log;
  const auto& traj = run.trajectory;
  identify::CurrentLog log;
  log.source = "full twin";
  const Eigen::Index K = L.values.rows();
  for (Eigen::MatrixXd* m : {&log.q, &log.qd, &log.qdd, &log.current}) m->resize(K, 6);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::VectorXd q(6), qd(6), qdd(6);
  for (Eigen::Index r = 0; r < K; ++r) {
    traj->evaluate(L.values(r, 0), q, qd, qdd);
    for (Eigen::Index j = 0; j < 6; ++j) {
      const std::string name = nominal.model().joint_names[static_cast<size_t>(j)];
      log.q(r, j) = std::round(L.values(r, L.column("q_fb_" + name + "[rad]")) * 1e6) * 1e-6;
      log.qd(r, j) = qd[j];
      log.qdd(r, j) = qdd[j];
      log.current(r, j) = std::round((L.values(r, L.column("current_" + name + "[A]")) + noise(rng)) * 1e3) * 1e-3;
    }
  }
  const Eigen::MatrixXd pred = identify::predictCurrents(nominal.model(), drives, log, known);
  const identify::CurrentFit fit = identify::fitDriveCurrents(nominal.model(), drives, log);
  for (int j = 0; j < 6; ++j) {
    const Eigen::VectorXd a = pred.col(j), b = log.current.col(j);
    EXPECT_NEAR(a.dot(b) / a.dot(a), 1.0, 0.005) << "joint " << j + 1;
    EXPECT_LT(std::sqrt((a - b).squaredNorm() / static_cast<double>(K)), 0.1) << "joint " << j + 1;
    const double s = fit.joints[static_cast<size_t>(j)].kt_scale.value,
                 s0 = known.joints[static_cast<size_t>(j)].kt_scale.value;
    EXPECT_NEAR(s, s0, 0.1 * s0) << "joint " << j + 1;
  }
}

TEST(CurrentCalibration, TheRefinementAgainstTheFullTwinRecoversItsDrives) {
  // As above, written as a log (500 Hz: commanded q, q̇, q̈ of the excitation, measured angles with 1e-6 rad steps,
  // currents with 0.01 A noise and 1 mA steps); calibrated by the command's path: the inner fit, then the
  // refinement whose replays (a tracking experiment of `type: log` over this log) are compared with the currents.
  const jointsim::test::TempDir tmp;
  const identify::CurrentFit known = truth(false);
  const systems::RobotSystem nominal = systems::loadRobotWithDrives(kDir + "robots/ur5_drives.yaml");
  const TwinExcitation run = twinExcitation(nominal, known);
  const auto& L = run.log;
  const auto& traj = run.trajectory;
  std::ofstream csv(tmp / "twin_log.csv");
  csv << "t_s";
  for (const char* c : {"q_target_", "qd_target_", "qdd_target_", "q_actual_", "i_actual_"})
    for (int j = 1; j <= 6; ++j) csv << "," << c << j;
  csv << "\n";
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::VectorXd q(6), qd(6), qdd(6);
  char cell[64];
  for (Eigen::Index r = 0; r < L.values.rows(); ++r) {
    const double t = L.values(r, 0);
    traj->evaluate(t, q, qd, qdd);
    std::snprintf(cell, sizeof cell, "%.6f", t);
    csv << cell;
    for (const Eigen::VectorXd* v : {&q, &qd, &qdd})
      for (int j = 0; j < 6; ++j) {
        std::snprintf(cell, sizeof cell, ",%.17g", (*v)[j]);
        csv << cell;
      }
    for (int j = 0; j < 6; ++j) {
      std::snprintf(cell, sizeof cell, ",%.6f",
                    L.values(r, L.column("q_fb_" + nominal.model().joint_names[static_cast<size_t>(j)] + "[rad]")));
      csv << cell;
    }
    for (int j = 0; j < 6; ++j) {
      const double i = L.values(r, L.column("current_" + nominal.model().joint_names[static_cast<size_t>(j)] + "[A]"));
      std::snprintf(cell, sizeof cell, ",%.3f", i + noise(rng));
      csv << cell;
    }
    csv << "\n";
  }
  csv.close();
  std::ofstream(tmp / "replay.yaml") << "experiment: {name: twin_replay, type: tracking}\n"
                                     << "robot: " << kDir << "robots/ur5_drives.yaml\n"
                                     << "trajectory:\n  type: log\n  file: twin_log.csv\n  columns:\n"
                                     << "    time: t_s\n    q: q_target_{j}\n    qd: qd_target_{j}\n"
                                     << "    qdd: qdd_target_{j}\n    q_measured: q_actual_{j}\n"
                                     << "relative_replay: false\nduration: 10\nlog_rate: 500\n"
                                     << "solver: {method: bdf, rtol: 1.0e-6, atol: 1.0e-9, max_order: 2}\n";
  identify::DriveCalibrationOptions o;
  o.refine_experiment = (tmp / "replay.yaml").string();
  const auto cal = identify::calibrateDrives(kDir + "robots/ur5_drives.yaml", (tmp / "twin_log.csv").string(), {}, o,
                                             (tmp / "drives.yaml").string());
  // Every parameter within 2 % of the truth (measured: within 0.6 %); the inner fit alone is 1–9 % off (above).
  for (int j = 0; j < 6; ++j) {
    const auto& f = cal.fit.joints[static_cast<size_t>(j)];
    const auto& t = known.joints[static_cast<size_t>(j)];
    EXPECT_NEAR(f.kt_scale.value, t.kt_scale.value, 0.02 * t.kt_scale.value) << "joint " << j + 1;
    EXPECT_NEAR(f.coulomb_pos.value, t.coulomb_pos.value, 0.02 * t.coulomb_pos.value) << "joint " << j + 1;
    EXPECT_NEAR(f.coulomb_neg.value, t.coulomb_neg.value, 0.02 * t.coulomb_neg.value) << "joint " << j + 1;
    EXPECT_NEAR(f.viscous_pos.value, t.viscous_pos.value, 0.02 * t.viscous_pos.value) << "joint " << j + 1;
    EXPECT_NEAR(f.viscous_neg.value, t.viscous_neg.value, 0.02 * t.viscous_neg.value) << "joint " << j + 1;
    EXPECT_LE(cal.refinement.rms_after[static_cast<size_t>(j)], cal.refinement.rms_before[static_cast<size_t>(j)]);
  }
  // The written file carries the refined values.
  EXPECT_NE(cal.drives_yaml.find("Refined against the full twin"), std::string::npos);
}

TEST(CurrentCalibration, TheShippedDrivesFileIsTheRefinedCalibrationsOutput) {
  // config/robots/ur5_drives_measured.yaml is `jointsim identify currents ... --refine ur5_measured_replay.yaml` on
  // the whole shipped log (33–36 replays, about 80 s: the slowest test of the identification; skipped in the sanitizer
  // build, where it would take several times as long and checks nothing that build adds).
  //
  // What is reproducible, and so checked: the inner fit and its replay (the "before" RMS of every joint within 0.1
  // point of % of range: an experimental change of the linear algebra's rounding, not kept, moved it by up to 0.02 —
  // the replay runs at rtol 1e-4 through stick–slip) and the quality the refinement reaches (the "after" RMS within 1 point of the
  // file's). What is not: the refined parameters themselves. The refinement is Levenberg–Marquardt on whole replays
  // through stick–slip, whose difference Jacobians move with the last bits of libm: on an AMD EPYC (glibc's FMA
  // variants of pow and sincos) it took 33 replays instead of 36 and ended with k_t up to 13 % away from the file
  // (elbow RMS 4.86 % instead of 4.29 %, the others within 0.1 point): this motion hardly separates a torque constant
  // from friction (docs/replay.md). So the parameters are compared with the file only as a note.
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the full calibration runs in the normal build";
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  GTEST_SKIP() << "the full calibration runs in the normal build";
#endif
#endif
  const jointsim::test::TempDir tmp;
  const std::string out = (tmp / "drives.yaml").string();
  const auto r = jointsim::test::runCli("identify currents " + kDir + "robots/ur5_drives.yaml " + kDir +
                                        "logs/ur5_kufieta2013_mov6_first30s.csv -o " + out + " --refine " + kDir +
                                        "experiments/ur5_measured_replay.yaml");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("refined against the full twin"));
  const systems::RobotSystem nominal = systems::loadRobotWithDrives(kDir + "robots/ur5_drives.yaml");
  const systems::RobotSystem cal = systems::loadRobotWithDrives(out);
  const systems::RobotSystem shipped = systems::loadRobotWithDrives(kDir + "robots/ur5_drives_measured.yaml");
  // The twin's RMS [% of range] before -> after, per joint: "JOINT ... twin rms[%R] B -> A" in the output,
  // "#   JOINT: B -> A %" in the file's header.
  std::ifstream header(kDir + "robots/ur5_drives_measured.yaml");
  const std::string file((std::istreambuf_iterator<char>(header)), std::istreambuf_iterator<char>());
  for (size_t k = 0; k < 6; ++k) {
    const std::string joint = nominal.model().joint_names[k];
    double run_before = 0.0, run_after = 0.0, file_before = 0.0, file_after = 0.0;
    const size_t at = r.out.find(joint + " ", r.out.find("refined against the full twin"));
    ASSERT_NE(at, std::string::npos) << joint;
    const size_t rms = r.out.find("twin rms[%R]", at);
    ASSERT_NE(rms, std::string::npos) << joint;
    ASSERT_EQ(std::sscanf(r.out.c_str() + rms, "twin rms[%%R] %lf -> %lf", &run_before, &run_after), 2) << joint;
    const size_t line = file.find("#   " + joint + ": ", file.find("Refined against the full twin"));
    ASSERT_NE(line, std::string::npos) << joint;
    ASSERT_EQ(std::sscanf(file.c_str() + line + 4 + joint.size() + 2, "%lf -> %lf", &file_before, &file_after), 2)
        << joint;
    EXPECT_NEAR(run_before, file_before, 0.1) << joint;
    EXPECT_NEAR(run_after, file_after, 1.0) << joint;
    EXPECT_LE(run_after, run_before) << joint;
    if (std::abs(shipped.drives()[k].motor.kt - cal.drives()[k].motor.kt) > 1e-4 * cal.drives()[k].motor.kt)
      std::printf("note: %s: k_t %.8g N*m/A here, %.8g in the shipped file (RMS %.2f %% here, %.2f %% there)\n",
                  joint.c_str(), cal.drives()[k].motor.kt, shipped.drives()[k].motor.kt, run_after, file_after);
    // Physically meaningful, both: within ±40 % of the nominal torque constant, friction >= 0.
    for (const systems::RobotSystem* sys : {&cal, &shipped}) {
      const double s = sys->drives()[k].motor.kt / nominal.drives()[k].motor.kt;
      EXPECT_GE(s, 0.6 - 1e-9) << joint;
      EXPECT_LE(s, 1.4 + 1e-9) << joint;
      const auto table = systems::driveParameterTable(sys->drives()[k], "friction");
      for (const char* key : {"positive.alpha0", "negative.alpha0", "positive.alpha2", "negative.alpha2"})
        EXPECT_GE(drive::parameterValue(table, key, "friction"), 0.0) << joint << " " << key;
    }
  }
}

TEST(CurrentCalibration, ARefinementReplayShorterThanTheLogIsAnError) {
  const jointsim::test::TempDir tmp;
  identify::DriveCalibrationOptions o;
  o.refine_experiment = kDir + "experiments/ur5_measured_replay.yaml";
  o.refine_overrides = {"duration=2"};
  EXPECT_THAT(
      [&] {
        identify::calibrateDrives(kDir + "robots/ur5_drives.yaml", kDir + "logs/ur5_kufieta2013_mov6_first30s.csv", {},
                                  o, (tmp / "drives.yaml").string());
      },
      ThrowsMessage<InputError>(
          HasSubstr("ur5_measured_replay.yaml: the replay ends at 2 s, before the log's window")));
}
