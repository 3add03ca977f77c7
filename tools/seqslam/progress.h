// A progress bar with the time left, on standard error, for the long commands (`sweep`,
// `eval` and `run` over long recordings). Drawn only when enabled (the callers enable it when
// standard error is a terminal and --quiet is off), so pipes and logs stay clean.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <mutex>
#include <string>

namespace seqslam::cli {

class Progress {
 public:
  Progress(size_t total, bool enabled) : total_(total), enabled_(enabled) {}
  // One more unit done (thread-safe).
  void step() { draw(++done_); }
  // `done` units done so far (done <= total).
  void update(size_t done) {
    done_ = done;
    draw(done);
  }

 private:
  void draw(size_t done) {
    if (!enabled_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return;
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double eta =
        done == 0 ? 0.0 : s / static_cast<double>(done) * static_cast<double>(total_ - done);
    const int width = 30;
    const int filled = total_ == 0 ? width : static_cast<int>(width * done / total_);
    std::fprintf(stderr, "\r[%s%s] %zu/%zu  %.0f s, about %.0f s left ",
                 std::string(static_cast<size_t>(filled), '#').c_str(),
                 std::string(static_cast<size_t>(width - filled), '.').c_str(), done, total_, s,
                 eta);
    if (done == total_) {
      std::fprintf(stderr, "\n");
      finished_ = true;
    }
  }

  size_t total_;
  bool enabled_;
  bool finished_ = false;
  std::atomic<size_t> done_{0};
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace seqslam::cli
