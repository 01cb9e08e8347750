#include "slam/frame_prefetch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <vector>

#include "splat/error.h"

namespace {

// A frame that says which index it was read for, and a record of every read.
struct Reads {
  std::mutex mutex;
  std::vector<std::size_t> indices;
  std::size_t failing = static_cast<std::size_t>(-1);
  app::FramePrefetch::Load load() {
    return [this](std::size_t i) {
      {
        std::lock_guard lock(mutex);
        indices.push_back(i);
      }
      if (i == failing) throw splat::Error("frame " + std::to_string(i) + ": unreadable");
      splat::RgbdFrame frame;
      frame.timestamp = static_cast<double>(i);
      return frame;
    };
  }
};

TEST(FramePrefetch, GivesEachFrameInOrderReadOnceAndNothingPastTheEnd) {
  Reads reads;
  {
    app::FramePrefetch prefetch(reads.load(), 3, 8);
    for (std::size_t i = 3; i < 8; ++i) EXPECT_EQ(prefetch.take(i).timestamp, static_cast<double>(i));
  }
  std::sort(reads.indices.begin(), reads.indices.end());  // reads run side by side
  EXPECT_EQ(reads.indices, (std::vector<std::size_t>{3, 4, 5, 6, 7}));
}

TEST(FramePrefetch, FollowsAnOrderAndReadsFramesTakenOutOfItThemselves) {
  Reads reads;
  {
    app::FramePrefetch prefetch(reads.load(), std::vector<std::size_t>{4, 1, 7});
    EXPECT_EQ(prefetch.take(4).timestamp, 4.0);
    EXPECT_EQ(prefetch.take(6).timestamp, 6.0);  // frame 1, read ahead, is not given instead
    EXPECT_EQ(prefetch.take(1).timestamp, 1.0);  // ... but when its turn comes
    EXPECT_EQ(prefetch.take(7).timestamp, 7.0);
    EXPECT_EQ(prefetch.take(4).timestamp, 4.0);  // again: read again
  }
  std::sort(reads.indices.begin(), reads.indices.end());
  EXPECT_EQ(reads.indices, (std::vector<std::size_t>{1, 4, 4, 6, 7}));
}

// The first frame's read finishes only once the second's has begun: with one read at a time it
// would wait for its bound and fail.
TEST(FramePrefetch, ReadsTwoFramesAtOnce) {
  std::mutex mutex;
  std::condition_variable changed;
  bool second_started = false;
  bool waited_out = false;
  app::FramePrefetch::Load load = [&](std::size_t i) {
    std::unique_lock lock(mutex);
    if (i == 1) {
      second_started = true;
      changed.notify_all();
    } else if (i == 0) {
      waited_out =
          !changed.wait_for(lock, std::chrono::seconds(60), [&] { return second_started; });
    }
    splat::RgbdFrame frame;
    frame.timestamp = static_cast<double>(i);
    return frame;
  };
  app::FramePrefetch prefetch(load, 0, 3);
  EXPECT_EQ(prefetch.take(0).timestamp, 0.0);
  EXPECT_FALSE(waited_out) << "frame 1 was not read while frame 0 was";
  EXPECT_EQ(prefetch.take(1).timestamp, 1.0);
  EXPECT_EQ(prefetch.take(2).timestamp, 2.0);
}

TEST(FramePrefetch, ThrowsAFramesReadErrorWhenThatFrameIsTaken) {
  Reads reads;
  reads.failing = 2;
  app::FramePrefetch prefetch(reads.load(), 0, 5);
  EXPECT_EQ(prefetch.take(0).timestamp, 0.0);
  EXPECT_EQ(prefetch.take(1).timestamp, 1.0);  // frame 2's read may already have failed
  try {
    prefetch.take(2);
    FAIL() << "frame 2's error was not thrown";
  } catch (const splat::Error& e) {
    EXPECT_STREQ(e.what(), "frame 2: unreadable");
  }
  EXPECT_EQ(prefetch.take(3).timestamp, 3.0);
}

}  // namespace
