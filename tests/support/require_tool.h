// For tests that need an outside tool (ROS 1, the MCAP reference writer): skips the test with
// `why` when `ok` is false, or fails it where GSLAM_REQUIRE_ROS_TESTS is defined (CI), so that a
// tool missing there is never a silent skip.
#pragma once
#include <gtest/gtest.h>

#ifdef GSLAM_REQUIRE_ROS_TESTS
#define GSLAM_REQUIRE_TOOL(ok, why) \
  if (!(ok)) GTEST_FAIL() << "required (GSLAM_REQUIRE_ROS_TESTS): " << (why)
#else
#define GSLAM_REQUIRE_TOOL(ok, why) \
  if (!(ok)) GTEST_SKIP() << (why)
#endif
