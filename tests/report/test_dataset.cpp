// HDF5 data sets of sweeps (report/dataset.hpp): what an interrupted or failed write leaves behind. The content
// is read back with h5py and pandas in tests/python/test_dataset.py.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/batch.hpp"
#include "jointsim/report/dataset.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace jointsim;

namespace {

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

// A two-run sweep whose run folders are written by hand (nothing is simulated), in a folder of the test's own (CTest
// runs the tests of this file in parallel).
struct HandMadeSweep {
  test::TempDir tmp;
  fs::path dir = tmp.path();
  experiments::Sweep sweep;
  HandMadeSweep() {
    write(dir / "sweep.yaml",
          "sweep: {name: hand, experiment: " + test::sourcePath("config/experiments/ur5_excitation.yaml") +
              "}\nruns:\n  - name: a\n  - name: b\n");
    sweep = experiments::loadSweep((dir / "sweep.yaml").string());
    for (const char* run : {"a", "b"}) {
      write(dir / "out" / run / "ur5_excitation.csv", "time[s],q_elbow_joint[rad]\n0,0.5\n0.01,0.25\n");
      write(dir / "out" / run / "summary.json", R"({"status": "ok", "sim_time_s": 0.01})");
    }
  }
  int leftovers() const {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir))
      n += e.path().filename().string().find(".tmp.") != std::string::npos;
    return n;
  }
};

}  // namespace

TEST(Dataset, AFailedWriteLeavesTheTargetUntouchedAndNoTemporaryFile) {
  HandMadeSweep h;
  const fs::path target = h.dir / "set.h5";
  write(target, std::string("\x89HDF\r\n\x1a\n", 8) + "an older data set");
  write(h.dir / "out" / "b" / "ur5_excitation.csv", "time[s],q_elbow_joint[rad]\n0,0.5\n0.01,oops\n");
  try {
    report::writeDataset(h.sweep, (h.dir / "out").string(), target.string());
    FAIL() << "a corrupt log must fail the write";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ur5_excitation.csv:3"), std::string::npos) << e.what();
  }
  EXPECT_EQ(test::readText(target), std::string("\x89HDF\r\n\x1a\n", 8) + "an older data set");
  EXPECT_EQ(h.leftovers(), 0);
  // Repaired, the same call replaces the old file by a complete HDF5 file in one rename.
  write(h.dir / "out" / "b" / "ur5_excitation.csv", "time[s],q_elbow_joint[rad]\n0,0.5\n0.01,0.25\n");
  const report::DatasetSummary s = report::writeDataset(h.sweep, (h.dir / "out").string(), target.string());
  EXPECT_EQ(s.runs, 2);
  EXPECT_EQ(s.runs_with_data, 2);
  EXPECT_EQ(s.samples, 4);
  EXPECT_EQ(test::readText(target).substr(0, 8), std::string("\x89HDF\r\n\x1a\n", 8));
  EXPECT_EQ(h.leftovers(), 0);
}

TEST(Dataset, AFolderThatDoesNotExistIsRejectedBeforeWriting) {
  HandMadeSweep h;
  const fs::path target = h.dir / "missing" / "set.h5";
  try {
    report::writeDataset(h.sweep, (h.dir / "out").string(), target.string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("folder '" + (h.dir / "missing").string() + "' does not exist"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(h.dir / "missing"));
  EXPECT_THROW(report::checkDatasetPath((h.dir / "out").string()), InputError);  // a folder, not a file name
}

TEST(Dataset, PendingRunsHaveLabelsButNoLog) {
  HandMadeSweep h;
  fs::remove_all(h.dir / "out" / "b");
  const report::DatasetSummary s = report::writeDataset(h.sweep, (h.dir / "out").string(), (h.dir / "set.h5").string());
  EXPECT_EQ(s.runs, 2);
  EXPECT_EQ(s.runs_with_data, 1);
}
