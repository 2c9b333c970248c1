// `jointsim fmu`: a good export writes one archive with the FMU's parts; bad input gives exit status 2, a message
// naming what was wrong, and no file (also no temporary one). The FMU's behaviour under an importer is tested in
// tests/fmi (the instance) and tests/python/test_fmu.py (FMPy).
#include <filesystem>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_util.hpp"

using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {
using Result = jointsim::test::CliResult;
Result run(const std::string& args) { return jointsim::test::runCli(args); }
const std::string kConfig = std::string(JOINTSIM_SOURCE_DIR) + "/config/experiments/";
}  // namespace

TEST(CliFmu, ExportsAnArchiveWithDescriptionBinaryAndResources) {
#ifndef JOINTSIM_HAS_FMU
  GTEST_SKIP() << "the FMU binary is not built in this configuration (sanitizers)";
#endif
  const jointsim::test::TempDir tmp;
  const fs::path dir = tmp.path();
  const Result r = run("fmu " + kConfig + "ur5_excitation.yaml -o " + (dir / "ur5_twin.fmu").string() +
                       " --inputs voltage --outputs q_shoulder_pan_joint,current_shoulder_pan_joint");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("'ur5_twin' with 6 inputs, 2 outputs"));
  ASSERT_TRUE(fs::exists(dir / "ur5_twin.fmu"));
  // The entry names stand in the zip's local headers and central directory (stored uncompressed).
  const std::string zip = jointsim::test::readText(dir / "ur5_twin.fmu");
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
  const jointsim::test::TempDir tmp;
  const fs::path dir = tmp.path();
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
      {kConfig + "msl_friction.yaml -o " + (dir / "m.fmu").string() + " --inputs command",
       "no input of mode 'command'"},
      {kConfig + "ur5_swg_joint_velocity.yaml -o " + (dir / "m.fmu").string() + " --inputs voltage", "command"},
      // A step size the FMI schema or any importer would refuse (before: a description FMPy rejects).
      {ur5 + " -o " + (dir / "m.fmu").string() + " --step-size nan", "step size"},
      {ur5 + " -o " + (dir / "m.fmu").string() + " --step-size inf", "step size"},
      {ur5 + " -o " + (dir / "m.fmu").string() + " --step-size -1", "step size"},
      {ur5 + " -o " + (dir / "m.fmu").string() + " --step-size 0", "step size"},
      {ur5 + " -o " + (dir / "m.fmu").string() + " --step-size 1e400", "step"},
      {ur5 + " -o " + (dir / "missing" / "m.fmu").string(), "does not exist"},  // bad input: exit 2 (was 1)
      // The checks of jointsim run (before: a log rate of 1e300 was exported and failed in the first doStep).
      {ur5 + " -o " + (dir / "m.fmu").string() + " --set log_rate=1e300", "limits.log_rows"},
  };
  for (const Case& c : cases) {
    const Result r = run("fmu " + c.args);
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.message)) << c.args;
  }
  EXPECT_TRUE(fs::is_empty(dir)) << "nothing written";
}
