// Throughput of the evaluation's SAD kernel (seqslam_tools/sad_simd.h) per SIMD target, and of
// the core's sad_many (what the evaluation ran before, and what the board runs), on one thread:
// 64 query images against a 3 600-image library at 32x16, the shape of `make bench-eval`.
// Counter "pairs/s": image comparisons per second.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "seqslam/difference.h"
#include "seqslam_tools/sad_simd.h"

namespace {

constexpr uint32_t kPixels = 32 * 16;
constexpr uint32_t kLibrary = 3600;
constexpr uint32_t kQueries = 64;

struct Images {
  std::vector<uint8_t> library;
  std::vector<uint8_t> queries;
  std::vector<uint32_t> sums;
  Images() : library(size_t{kLibrary} * kPixels), queries(size_t{kQueries} * kPixels) {
    std::mt19937 rng(7);
    for (uint8_t& p : library)
      p = static_cast<uint8_t>(rng());
    for (uint8_t& p : queries)
      p = static_cast<uint8_t>(rng());
    for (uint32_t j = 0; j < kLibrary; ++j)
      sums.push_back(seqslam::pixel_sum(&library[size_t{j} * kPixels], kPixels));
  }
};

const Images& images() {
  static const Images i;
  return i;
}

void set_counters(benchmark::State& state) {
  state.counters["pairs/s"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * kQueries * kLibrary, benchmark::Counter::kIsRate);
}

void bench_simd(benchmark::State& state, int64_t target) {
  seqslam::tools::sad_force_target(target);
  const Images& im = images();
  std::vector<uint32_t> out(size_t{kQueries} * kLibrary);
  for (auto _ : state) {
    seqslam::tools::sad_rows(im.queries.data(), kQueries, im.library.data(), kLibrary, kPixels,
                             out.data(), kLibrary);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  seqslam::tools::sad_force_target(0);
  set_counters(state);
}

void bench_core(benchmark::State& state) {
  const Images& im = images();
  std::vector<uint32_t> out(size_t{kQueries} * kLibrary);
  for (auto _ : state) {
    for (uint32_t q = 0; q < kQueries; ++q) {
      seqslam::sad_many(&im.queries[size_t{q} * kPixels], im.library.data(), im.sums.data(),
                        kLibrary, kPixels, &out[size_t{q} * kLibrary]);
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  set_counters(state);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::RegisterBenchmark("core sad_many", bench_core)->Unit(benchmark::kMillisecond);
  for (const int64_t t : seqslam::tools::sad_available_targets()) {
    const std::string name = std::string("sad_rows ") + seqslam::tools::sad_target_name(t);
    benchmark::RegisterBenchmark(name.c_str(), bench_simd, t)->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
