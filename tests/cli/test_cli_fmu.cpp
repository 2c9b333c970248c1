// `jointsim fmu`: a good export writes one archive with the FMU's parts; bad input gives exit status 2, a message
// naming what was wrong, and no file (also no temporary one). The FMU's behaviour under an importer is tested in
// tests/fmi (the instance) and tests/python/test_fmu.py (FMPy).
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {
struct Result {
  int status;
  std::string out, err;
};
Result run(const std::string& args) {
  const auto base = fs::temp_directory_path() / "jointsim_fmu_cli";
  const std::string cmd = std::string(JOINTSIM_CLI_PATH) + " " + args + " >" + base.string() + ".out 2>" +
                          base.string() + ".err";
  const int rc = std::system(cmd.c_str());
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, slurp(base.string() + ".out"), slurp(base.string() + ".err")};
}
const std::string kConfig = std::string(JOINTSIM_SOURCE_DIR) + "/config/experiments/";
}  // namespace

TEST(CliFmu, ExportsAnArchiveWithDescriptionBinaryAndResources) {
#ifndef JOINTSIM_HAS_FMU
  GTEST_SKIP() << "the FMU binary is not built in this configuration (sanitizers)";
#endif
  const auto dir = fs::temp_directory_path() / "jointsim_fmu_cli_good";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Result r = run("fmu " + kConfig + "ur5_excitation.yaml -o " + (dir / "ur5_twin.fmu").string() +
                       " --inputs voltage --outputs q_shoulder_pan_joint,current_shoulder_pan_joint");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("'ur5_twin' with 6 inputs, 2 outputs"));
  ASSERT_TRUE(fs::exists(dir / "ur5_twin.fmu"));
  // The archive's table of contents (unzip -Z1 from Debian's unzip when present, else the zip's own bytes).
  std::ifstream in(dir / "ur5_twin.fmu", std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  const std::string zip = bytes.str();
  for (const char* part : {"modelDescription.xml", "binaries/linux64/ur5_twin.so", "resources/jointsim_fmu.json",
                           "resources/experiments/ur5_excitation.yaml", "resources/robots/ur5_drives.yaml",
                           "resources/robots/ur5.yaml", "binaries/linux64/libsundials_cvode.so"})
    EXPECT_NE(zip.find(part), std::string::npos) << part;
  EXPECT_EQ(zip.compare(0, 4, "PK\x03\x04"), 0);
  size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) entries += e.is_regular_file();
  EXPECT_EQ(entries, 1u) << "no temporary file left";
}

TEST(CliFmu, BadInputExitTwoAndNothingWritten) {
  const auto dir = fs::temp_directory_path() / "jointsim_fmu_cli_bad";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string ur5 = kConfig + "ur5_excitation.yaml";
  struct Case {
    std::string args, message;
  } cases[] = {
      {ur5 + " -o " + (dir / "1bad.fmu").string(), "must be a C identifier"},
      {ur5 + " -o " + (dir / "m.zip").string(), "must end in .fmu"},
      {ur5 + " -o " + (dir / "m.fmu").string() + " --inputs torque", "torque"},
      {ur5 + " -o " + (dir / "m.fmu").string() + " --inputs elbow:voltage", "elbow"},
      {ur5 + " -o " + (dir / "m.fmu").string() + " --inputs voltage,elbow_joint:current", "two command ports"},
      {ur5 + " -o " + (dir / "m.fmu").string() + " --outputs no_such_signal", "no_such_signal"},
      {ur5 + " -o " + (dir / "m.fmu").string() + " --set no.such.key=1", "no.such.key"},
      {kConfig + "msl_friction.yaml -o " + (dir / "m.fmu").string(), "not supported"},
      {kConfig + "ur5_swg_joint_velocity.yaml -o " + (dir / "m.fmu").string() + " --inputs voltage", "command"},
  };
  for (const Case& c : cases) {
    const Result r = run("fmu " + c.args);
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.message)) << c.args;
  }
  EXPECT_TRUE(fs::is_empty(dir)) << "nothing written";
}
