// BlockRunner (rsvio/frontend/block_runner.h): every block exactly once, on either thread count, also
// when the blocks' costs are very unequal (the two threads take blocks as they come free).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "rsvio/frontend/block_runner.h"

namespace rsvio {
namespace {

TEST(BlockRunner, CallsEveryBlockExactlyOnceOnOneAndTwoThreads) {
  for (int threads : {1, 2}) {
    BlockRunner runner(threads);
    EXPECT_EQ(runner.threads(), threads);
    for (int n : {0, 1, 2, 3, 16, 49, 1000}) {
      std::vector<std::atomic<int>> calls(static_cast<size_t>(n));
      for (auto& c : calls) c = 0;
      runner.run(n, [&](int b) { calls[static_cast<size_t>(b)].fetch_add(1); });
      for (int b = 0; b < n; ++b) EXPECT_EQ(calls[static_cast<size_t>(b)].load(), 1) << "threads " << threads << " n " << n << " block " << b;
    }
  }
}

TEST(BlockRunner, UnequalBlocksAreSharedBetweenTheThreads) {
  // Block 0 is slow: it waits (at most 10 s) until the other blocks are done. With a fixed even/odd
  // split its thread would run every other even block after it; taken as they come free, the other
  // thread runs all of them meanwhile.
  BlockRunner runner(2);
  const int n = 9;
  std::vector<std::thread::id> who(n);
  std::atomic<int> done{0};
  runner.run(n, [&](int b) {
    if (b == 0) {
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
      while (done.load() < n - 1 && std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    who[static_cast<size_t>(b)] = std::this_thread::get_id();
    done.fetch_add(1);
  });
  int with_block0 = 0;
  for (int b = 1; b < n; ++b) with_block0 += who[static_cast<size_t>(b)] == who[0] ? 1 : 0;
  EXPECT_EQ(with_block0, 0) << "the thread that ran the slow block also ran " << with_block0 << " others";
}

TEST(BlockRunner, PerBlockSumsCombinedInOrderAreTheSameOnBothThreadCounts) {
  const int n = 37;
  auto sum = [&](int threads) {
    BlockRunner runner(threads);
    std::vector<double> part(n, 0.0);
    runner.run(n, [&](int b) {
      for (int i = 0; i < 1000 * (b % 5 + 1); ++i) part[static_cast<size_t>(b)] += 1.0 / (1.0 + b * 1000.0 + i);
    });
    double s = 0;
    for (double p : part) s += p;
    return s;
  };
  EXPECT_EQ(sum(1), sum(2));  // bit for bit
}

}  // namespace
}  // namespace rsvio
