#include "splat/thread_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace {

// Every index of every job runs exactly once, also when jobs of a few items follow each other
// faster than the workers wake (a worker may arrive after its job has ended).
TEST(ThreadPool, RunsEveryItemOnceAcrossManyShortJobs) {
  for (int threads : {1, 2, 4}) {
    splat::ThreadPool pool(threads);
    for (std::size_t job = 0; job < 3000; ++job) {
      const std::size_t n = 1 + job % 7;
      std::vector<std::atomic<int>> runs(n);
      pool.parallel_for(n, [&](std::size_t i) { runs[i].fetch_add(1); });
      for (std::size_t i = 0; i < n; ++i)
        ASSERT_EQ(runs[i].load(), 1) << threads << " threads, job " << job << ", item " << i;
    }
    std::vector<int> big(100000, 0);
    pool.parallel_for(big.size(), [&](std::size_t i) { big[i] = static_cast<int>(i) * 3; });
    for (std::size_t i = 0; i < big.size(); ++i) ASSERT_EQ(big[i], static_cast<int>(i) * 3);
  }
}

TEST(ThreadPool, RethrowsAnItemsExceptionAfterTheOthersRanAndStaysUsable) {
  splat::ThreadPool pool(2);
  std::atomic<int> ran{0};
  EXPECT_THROW(pool.parallel_for(64,
                                 [&](std::size_t i) {
                                   ran.fetch_add(1);
                                   if (i == 5) throw std::runtime_error("item 5");
                                 }),
               std::runtime_error);
  EXPECT_EQ(ran.load(), 64);  // the job ends only when every item has run
  std::atomic<int> after{0};
  pool.parallel_for(10, [&](std::size_t) { after.fetch_add(1); });
  EXPECT_EQ(after.load(), 10);
}

// Workers that are polling for the next job, or asleep, stop when the pool goes away.
TEST(ThreadPool, StopsWhileItsWorkersWaitForWork) {
  for (int round = 0; round < 50; ++round) {
    splat::ThreadPool pool(3);
    std::atomic<int> sum{0};
    if (round % 2 == 0)
      pool.parallel_for(3, [&](std::size_t i) { sum.fetch_add(static_cast<int>(i)); });
    EXPECT_EQ(sum.load(), round % 2 == 0 ? 3 : 0);
  }
}

}  // namespace
