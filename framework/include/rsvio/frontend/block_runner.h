// Runs a function over numbered blocks on at most two threads, for deterministic parallel sums.
//
// Contract
// - run(n, f) calls f(b) exactly once for every b in [0, n) and returns when all calls are done.
//   With two threads the calling thread and one persistent worker take the next block not yet taken
//   (an atomic counter), so blocks of unequal cost balance; which thread ran a block is not fixed.
// - Callers make results independent of the thread count by giving every block its own output and
//   combining them in block order afterwards (conventions.md, "Determinism": parallel sums in a fixed
//   order). f must not throw; a block that fails records it in its own output.
// - One run at a time per runner (it is not re-entrant); the worker sleeps between runs.
#pragma once
#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace rsvio {

class BlockRunner {
 public:
  explicit BlockRunner(int threads);
  ~BlockRunner();
  BlockRunner(const BlockRunner&) = delete;
  BlockRunner& operator=(const BlockRunner&) = delete;

  int threads() const { return worker_.joinable() ? 2 : 1; }
  void run(int num_blocks, const std::function<void(int)>& f);

 private:
  void workerLoop();

  std::thread worker_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  const std::function<void(int)>* job_ = nullptr;
  int num_blocks_ = 0;
  std::atomic<int> next_{0};  // the next block to take
  long generation_ = 0;
  bool worker_busy_ = false;
  bool stop_ = false;
};

}  // namespace rsvio
