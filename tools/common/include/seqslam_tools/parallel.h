// A minimal parallel loop for the host tools and the simulator: job(0) .. job(count - 1) on up
// to `threads` threads, each index exactly once, in no particular order. The jobs must be
// independent (results that depend on the order would break the tools' determinism).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace seqslam::tools {

// 0 threads = all cores.
inline unsigned resolve_threads(unsigned requested) {
  if (requested != 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : hw;
}

template <typename Job>
void parallel_for(size_t count, unsigned threads, const Job& job) {
  threads = std::max(1u, std::min<unsigned>(resolve_threads(threads),
                                            static_cast<unsigned>(std::max<size_t>(count, 1))));
  if (threads == 1) {
    for (size_t i = 0; i < count; ++i)
      job(i);
    return;
  }
  std::atomic<size_t> next{0};
  std::vector<std::thread> pool;
  pool.reserve(threads);
  for (unsigned t = 0; t < threads; ++t) {
    pool.emplace_back([&] {
      for (size_t i = next++; i < count; i = next++)
        job(i);
    });
  }
  for (std::thread& th : pool)
    th.join();
}

}  // namespace seqslam::tools
