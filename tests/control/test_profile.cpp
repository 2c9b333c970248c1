// Input profiles: values at known times, breakpoints, CSV loading and its errors.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/control/profile.hpp"
#include "test_util.hpp"

using jointsim::control::Profile;
using ::testing::HasSubstr;

TEST(Profile, ClosedFormValues) {
  EXPECT_EQ(Profile::constant(2.5).value(7.0), 2.5);
  const Profile step = Profile::step(1.0, 3.0, 0.5);
  EXPECT_EQ(step.value(0.49), 1.0);
  EXPECT_EQ(step.value(0.5), 3.0);
  const Profile ramp = Profile::ramp(1.0, 2.0, 1.0, 3.0);
  EXPECT_EQ(ramp.value(0.5), 1.0);
  EXPECT_DOUBLE_EQ(ramp.value(2.0), 3.0);
  EXPECT_DOUBLE_EQ(ramp.value(10.0), 5.0);
  const Profile tri = Profile::triangle(3.0, 40.0, 0.5);
  EXPECT_DOUBLE_EQ(tri.value(0.0), 0.5);
  EXPECT_DOUBLE_EQ(tri.value(10.0), 3.5);
  EXPECT_DOUBLE_EQ(tri.value(20.0), 0.5);
  EXPECT_DOUBLE_EQ(tri.value(30.0), -2.5);
  EXPECT_DOUBLE_EQ(tri.value(45.0), 2.0);
  const Profile sine = Profile::sine(2.0, 0.25, 0.0, 1.0);
  EXPECT_NEAR(sine.value(1.0), 3.0, 1e-15);
  const Profile pw = Profile::piecewise({0, 1, 3}, {0, 10, -10});
  EXPECT_DOUBLE_EQ(pw.value(0.5), 5.0);
  EXPECT_DOUBLE_EQ(pw.value(2.0), 0.0);
  EXPECT_DOUBLE_EQ(pw.value(9.0), -10.0);
  EXPECT_DOUBLE_EQ(Profile::piecewise({0, 1, 3}, {0, 10, -10}, true).value(2.9), 10.0);
}

TEST(Profile, BreakpointsWithinHorizon) {
  EXPECT_EQ(Profile::step(0, 1, 0.5).breakpoints(1.0), std::vector<double>({0.5}));
  EXPECT_EQ(Profile::triangle(1, 4).breakpoints(7.0), std::vector<double>({1.0, 3.0, 5.0}));
  EXPECT_TRUE(Profile::sine(1, 1).breakpoints(10.0).empty());
}

TEST(Profile, CsvLinearInterpolationAndErrors) {
  const jointsim::test::TempDir tmp;
  const auto dir = tmp.path();
  const auto good = dir / "jointsim_profile.csv";
  std::ofstream(good) << "time[s],torque[N·m],other\n0,0,5\n1,2,5\n3,-2,5\n";
  const Profile p = Profile::csv(good.string());
  EXPECT_DOUBLE_EQ(p.value(0.5), 1.0);
  EXPECT_DOUBLE_EQ(p.value(2.0), 0.0);
  EXPECT_DOUBLE_EQ(Profile::csv(good.string(), "other").value(2.0), 5.0);
  const auto bad = dir / "jointsim_profile_bad.csv";
  std::ofstream(bad) << "t,v\n0,1\n1,oops\n";
  EXPECT_THAT([&] { Profile::csv(bad.string()); },
              ::testing::ThrowsMessage<jointsim::InputError>(
                  HasSubstr("jointsim_profile_bad.csv:3:2: column 'v': expected a number, got 'oops'")));
  EXPECT_THAT([&] { Profile::csv((dir / "missing_profile.csv").string()); },
              ::testing::ThrowsMessage<jointsim::InputError>(
                  HasSubstr("missing_profile.csv: cannot open CSV file for reading")));
  EXPECT_THAT([&] { Profile::csv(good.string(), "nope"); },
              ::testing::ThrowsMessage<jointsim::InputError>(HasSubstr(":1: no column named 'nope'")));
}
