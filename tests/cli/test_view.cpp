// `jointsim view` (report::viewHtml, writeView): the page's data read back from the HTML and checked against the
// run folder it came from — every drawn sample a row of the CSV, the peaks of every slice kept, the arm's kinematics
// those of the model file, the data inert inside its script element — and the errors (InputError, exit 2, nothing
// written). The browser half (drawing, scrubbing, no network) is tests/python/test_view_browser.py.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/data.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/report/view.hpp"
#include "test_util.hpp"

using ::testing::HasSubstr;
using jointsim::test::sourcePath;
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

using Scratch = jointsim::test::TempDir;

/// The page's data: the JSON inside <script type="application/json" id="jointsim-data">.
json pageData(const std::string& html) {
  const std::string open = "id=\"jointsim-data\">";
  const auto a = html.find(open);
  EXPECT_NE(a, std::string::npos);
  const auto b = html.find("</script>", a);
  return json::parse(html.substr(a + open.size(), b - a - open.size()));
}

/// A run folder of a generic experiment type (every column against time) with the given log.
void writeRun(const fs::path& dir, const std::string& header, const std::vector<std::vector<double>>& rows,
              const json& extra = json::object()) {
  fs::create_directories(dir);
  std::ofstream csv(dir / "r.csv");
  csv.precision(17);
  csv << header << "\n";
  for (const auto& r : rows) {
    for (size_t i = 0; i < r.size(); ++i) csv << (i ? "," : "") << r[i];
    csv << "\n";
  }
  json s = {{"experiment", "r"}, {"type", "custom"}, {"status", "ok"}};
  s.update(extra);
  std::ofstream(dir / "summary.json") << s.dump();
}

TEST(View, EverySampleIsARowOfTheLogAndEverySlicesPeaksAreKept) {
  Scratch tmp;
  // A 20,000-row signal with a narrow spike of one row and a dip elsewhere, drawn in 50 slices.
  std::vector<std::vector<double>> rows;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double t = i * 1e-3;
    double y = std::sin(7.0 * t) + 0.01 * std::sin(900.0 * t);
    if (i == 12345) y = 40.0;
    if (i == 777) y = -30.0;
    rows.push_back({t, y});
  }
  writeRun(tmp / "run", "time[s],y[N·m]", rows);
  jointsim::report::ViewOptions o;
  o.columns = 50;
  const json d = pageData(jointsim::report::viewHtml((tmp / "run").string(), o));
  const json& run = d["runs"][0];
  const json& s = run["figures"][0]["panels"][0]["series"][0];
  const json& time = run["time"];
  ASSERT_LE(s["xi"].size(), 3u * 50u);
  std::vector<int> drawn_rows;
  for (size_t k = 0; k < s["xi"].size(); ++k) {
    const double t = time[s["xi"][k].get<size_t>()].get<double>();
    const int row = static_cast<int>(std::lround(t / 1e-3));
    ASSERT_EQ(rows[static_cast<size_t>(row)][0], t);  // a time of the log, exactly
    EXPECT_NEAR(s["y"][k].get<double>(), rows[static_cast<size_t>(row)][1], 1e-7 * 40) << "row " << row;
    drawn_rows.push_back(row);
  }
  // Per slice (equal runs of rows) the rows of its minimum and maximum are drawn.
  for (int sl = 0; sl < 50; ++sl) {
    const int a = n * sl / 50, b = n * (sl + 1) / 50;
    int lo = a, hi = a;
    for (int i = a; i < b; ++i) {
      if (rows[static_cast<size_t>(i)][1] < rows[static_cast<size_t>(lo)][1]) lo = i;
      if (rows[static_cast<size_t>(i)][1] > rows[static_cast<size_t>(hi)][1]) hi = i;
    }
    EXPECT_NE(std::find(drawn_rows.begin(), drawn_rows.end(), lo), drawn_rows.end()) << "slice " << sl;
    EXPECT_NE(std::find(drawn_rows.begin(), drawn_rows.end(), hi), drawn_rows.end()) << "slice " << sl;
  }
  EXPECT_NE(std::find(drawn_rows.begin(), drawn_rows.end(), 12345), drawn_rows.end());
  EXPECT_NE(std::find(drawn_rows.begin(), drawn_rows.end(), 777), drawn_rows.end());
  EXPECT_EQ(s["unit"], "N·m");
  EXPECT_TRUE(d["arm"].is_null());
  EXPECT_THAT(d["arm_note"].get<std::string>(), HasSubstr("no parameters.config"));
}

TEST(View, DataCannotLeaveItsScriptElementNorBecomeMarkup) {
  Scratch tmp;
  const std::string evil = "</script><script>alert(1)</script><!--<img src=x onerror=alert(2)>&amp;\u2028";
  writeRun(tmp / "run", "time[s],v</script>[A]", {{0.0, 1.0}, {0.1, NAN}, {0.2, INFINITY}, {0.3, 1e308}},
           {{"status", evil}, {"parameters", {{"x", evil}}}});
  const std::string html = jointsim::report::viewHtml((tmp / "run").string());
  // The only script elements are the page's own five and the data element; the data holds no '<', '>' or '&'.
  size_t scripts = 0;
  for (auto k = html.find("<script"); k != std::string::npos; k = html.find("<script", k + 1)) ++scripts;
  EXPECT_EQ(scripts, 5u);
  size_t closes = 0;
  for (auto k = html.find("</script"); k != std::string::npos; k = html.find("</script", k + 1)) ++closes;
  EXPECT_EQ(closes, scripts);  // the data's own "</script>" is not among them
  const auto a = html.find("id=\"jointsim-data\">"), b = html.find("</script>", a);
  const std::string payload = html.substr(a + 19, b - a - 19);
  EXPECT_EQ(payload.find_first_of("<>&"), std::string::npos);
  // The text survives as data: the page shows it as text.
  const json d = pageData(html);
  EXPECT_EQ(d["runs"][0]["summary"]["status"], evil);
  const json& y = d["runs"][0]["figures"][0]["panels"][0]["series"][0]["y"];
  EXPECT_TRUE(y[1].is_null());
  EXPECT_TRUE(y[2].is_null());
  EXPECT_EQ(y[3].get<double>(), 1e308);
  // A Content-Security-Policy without network access, the page's scripts allowed by nonce only.
  EXPECT_THAT(html, HasSubstr("default-src 'none'; script-src 'nonce-"));
}

TEST(View, TheArmIsTheModelFilesKinematicsAtTheLoggedAngles) {
  Scratch tmp;
  jointsim::experiments::RunOptions options;
  options.output_dir = (tmp / "run").string();
  options.overrides = {"duration=0.2"};
  ASSERT_EQ(
      jointsim::experiments::runExperimentFile(sourcePath("config/experiments/ur5_excitation.yaml"), options).status,
      "ok");
  const json d = pageData(jointsim::report::viewHtml((tmp / "run").string()));
  const auto model = jointsim::multibody::loadRobot(sourcePath("config/robots/ur5.yaml"));
  const json& arm = d["arm"];
  ASSERT_EQ(arm["joints"].size(), static_cast<size_t>(model.nq));
  for (int i = 0; i < model.nq; ++i) {
    const json& j = arm["joints"][static_cast<size_t>(i)];
    const auto k = static_cast<size_t>(i);
    EXPECT_EQ(j["name"], model.joint_names[k]);
    EXPECT_EQ(j["parent"], model.parents[k]);
    EXPECT_EQ(j["column"], "q_" + model.joint_names[k]);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(j["origin"]["p"][static_cast<size_t>(c)].get<double>(), model.joint_placements[k].p[c]);
      EXPECT_EQ(j["axis"][static_cast<size_t>(c)].get<double>(), model.axes[k][c]);
    }
  }
  // The TCP path is the logged TCP (the run's own kinematics): same points.
  const auto log = jointsim::io::readCsv((tmp / "run" / "ur5_excitation.csv").string(), false);
  auto col = [&](const std::string& name) {
    const auto it = std::find(log.header.begin(), log.header.end(), name);
    return static_cast<Eigen::Index>(it - log.header.begin());
  };
  const json& motion = d["runs"][0]["motion"];
  ASSERT_EQ(motion["xi"].size(), static_cast<size_t>(log.data.rows()));  // 0.2 s at 500 Hz: every row
  const json& path = motion["tcp_path"];
  ASSERT_GE(path.size(), 50u);
  for (size_t k = 0; k < path.size(); ++k)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(path[k][static_cast<size_t>(c)].get<double>(),
                  log.data(static_cast<Eigen::Index>(k), col(std::string("tcp_") + "xyz"[c] + "[m]")), 1e-12);
}

TEST(View, ErrorsNameTheFolderAndNothingIsWritten) {
  Scratch tmp;
  EXPECT_THROW(jointsim::report::viewHtml((tmp / "missing").string()), jointsim::InputError);
  fs::create_directories(tmp / "empty");
  try {
    jointsim::report::viewHtml((tmp / "empty").string());
    FAIL() << "no error";
  } catch (const jointsim::InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("neither a run folder"));
  }
  writeRun(tmp / "run", "time[s],y[-]", {{0, 1}, {1, 2}});
  jointsim::report::ViewOptions bad;
  bad.columns = 5;
  EXPECT_THROW(jointsim::report::viewHtml((tmp / "run").string(), bad), jointsim::InputError);
  const auto r = jointsim::test::runCli("view " + jointsim::test::shellQuote((tmp / "empty").string()) + " -o " +
                                        jointsim::test::shellQuote((tmp / "page.html").string()));
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("neither a run folder"));
  EXPECT_FALSE(fs::exists(tmp / "page.html"));
  // A good folder: the page at DIR/view.html, written whole (no temporary file left).
  const auto ok = jointsim::test::runCli("view " + jointsim::test::shellQuote((tmp / "run").string()));
  ASSERT_EQ(ok.status, 0) << ok.err;
  EXPECT_THAT(ok.out, HasSubstr("view.html"));
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(tmp / "run")) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"r.csv", "summary.json", "view.html"}));
}

TEST(View, ASweepRunOnAnotherRobotIsListedButNotAnimatedWithTheFirstRunsArm) {
  Scratch tmp;
  for (const auto& [name, robot] : std::vector<std::pair<std::string, std::string>>{
           {"a", "../robots/ur5_drives.yaml"}, {"b", "../robots/ur5_drives_elastic.yaml"}}) {
    jointsim::experiments::RunOptions options;
    options.output_dir = (tmp / "sweep" / name).string();
    options.overrides = {"duration=0.05", "robot=" + robot};
    ASSERT_EQ(
        jointsim::experiments::runExperimentFile(sourcePath("config/experiments/ur5_excitation.yaml"), options).status,
        "ok");
  }
  std::ofstream(tmp / "sweep" / "manifest.csv") << "run,status,wall_time_s,sim_time_s,real_time_factor,output_dir,"
                                                   "overrides\na,ok,1,0.05,1,a,\nb,ok,1,0.05,1,b,\n";
  const json d = pageData(jointsim::report::viewHtml((tmp / "sweep").string()));
  ASSERT_EQ(d["runs"].size(), 2u);
  EXPECT_TRUE(d["runs"][0].contains("motion"));
  EXPECT_FALSE(d["runs"][1].contains("motion"));
  EXPECT_THAT(d["runs"][1]["motion_note"].get<std::string>(), HasSubstr("robot differs"));
  EXPECT_TRUE(d["runs"][1].contains("key"));  // still overlaid
}

}  // namespace
