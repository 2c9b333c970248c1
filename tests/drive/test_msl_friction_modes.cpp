// The mode logic of the MSL stick-slip friction (drive::nextFrictionMode) at the instants where it decides on
// rounding-level numbers: a start phase entered at a located break-away root, where the acceleration is zero
// to rounding (no breakaway peak, τ0max = τ0), must go on; only a real exit from the start region locks again.
#include <gtest/gtest.h>

#include "jointsim/drive/msl_friction.hpp"

using jointsim::drive::FrictionEventFlags;
using jointsim::drive::FrictionMode;
using jointsim::drive::nextFrictionMode;

namespace {
const double t0 = 0.7, t0max = 0.7;  // [N·m], RobotR3 axis 3: no breakaway peak
FrictionEventFlags none() { return {}; }
FrictionEventFlags second(bool falling) {
  FrictionEventFlags f;
  f.second = true;
  f.down = falling;
  return f;
}
}  // namespace

TEST(MslFrictionModes, BreakAwayAtTheRootEntersTheStartPhase) {
  // Stuck, the stuck torque located on −τ0max (to rounding on either side), the crossing reported.
  FrictionEventFlags down;
  down.down = down.second = true;
  EXPECT_EQ(nextFrictionMode(FrictionMode::Stuck, false, -t0max + 1e-16, 0.0, 0.0, t0, t0max, down),
            FrictionMode::StartBackward);
  EXPECT_EQ(nextFrictionMode(FrictionMode::Stuck, false, -t0max - 2e-16, 0.0, 0.0, t0, t0max, none()),
            FrictionMode::StartBackward);
  EXPECT_EQ(nextFrictionMode(FrictionMode::Stuck, false, -t0max + 1e-3, 0.0, 0.0, t0, t0max, none()),
            FrictionMode::Stuck);
}

TEST(MslFrictionModes, StartPhaseWithRoundingLevelAccelerationGoesOn) {
  // Just after entering StartBackward at the root: a = (S + τ0)/J ≈ 0, here +1e-12 rad/s² by rounding. It used
  // to lock again at once (and the next iteration broke away again: the event ended on whichever came last).
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartBackward, false, 0.0, 0.0, 1e-12, t0, t0max, none()),
            FrictionMode::StartBackward);
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartForward, false, 0.0, 0.0, -1e-12, t0, t0max, none()),
            FrictionMode::StartForward);
  // A clear exit (the acceleration turned against the start direction) locks.
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartBackward, false, 0.0, 0.0, 1e-3, t0, t0max, none()),
            FrictionMode::Stuck);
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartForward, false, 0.0, 0.0, -1e-3, t0, t0max, none()),
            FrictionMode::Stuck);
  // With a breakaway peak the start region is wide: a = 0 is well inside it.
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartForward, false, 0.0, 0.0, 0.0, 21.8, 26.7, none()),
            FrictionMode::StartForward);
}

TEST(MslFrictionModes, OnlyACrossingOutOfTheStartRegionLocks) {
  // Exit function g = a − τ0max + τ0 of StartBackward: rising through 0 leaves the region (lock), falling
  // through 0 enters it (the start goes on). StartForward's g = a + τ0max − τ0: the other way round.
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartBackward, false, 0.0, 0.0, 1e-15, t0, t0max, second(false)),
            FrictionMode::Stuck);
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartBackward, false, 0.0, 0.0, -1e-15, t0, t0max, second(true)),
            FrictionMode::StartBackward);
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartForward, false, 0.0, 0.0, -1e-15, t0, t0max, second(true)),
            FrictionMode::Stuck);
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartForward, false, 0.0, 0.0, 1e-15, t0, t0max, second(false)),
            FrictionMode::StartForward);
  // Reaching the sliding speed ends the start phase in the sliding mode.
  FrictionEventFlags w;
  w.w = true;
  EXPECT_EQ(nextFrictionMode(FrictionMode::StartBackward, false, 0.0, -1e-10, -1.0, t0, t0max, w),
            FrictionMode::Backward);
}
