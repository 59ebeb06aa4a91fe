#include "rsvio/frontend/block_runner.h"

namespace rsvio {

BlockRunner::BlockRunner(int threads) {
  if (threads >= 2) worker_ = std::thread([this] { workerLoop(); });
}

BlockRunner::~BlockRunner() {
  if (!worker_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  worker_.join();
}

void BlockRunner::workerLoop() {
  long seen = 0;
  for (;;) {
    const std::function<void(int)>* job = nullptr;
    int n = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      job = job_;
      n = num_blocks_;
    }
    for (int b; (b = next_.fetch_add(1, std::memory_order_relaxed)) < n;) (*job)(b);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      worker_busy_ = false;
    }
    done_.notify_one();
  }
}

void BlockRunner::run(int num_blocks, const std::function<void(int)>& f) {
  if (!worker_.joinable() || num_blocks < 2) {
    for (int b = 0; b < num_blocks; ++b) f(b);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &f;
    num_blocks_ = num_blocks;
    worker_busy_ = true;
    next_.store(0, std::memory_order_relaxed);
    ++generation_;
  }
  wake_.notify_one();
  for (int b; (b = next_.fetch_add(1, std::memory_order_relaxed)) < num_blocks;) f(b);
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return !worker_busy_; });
  job_ = nullptr;
}

}  // namespace rsvio
