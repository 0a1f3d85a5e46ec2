// The machine's streaming bandwidth: a copy of 256 MiB (far beyond the caches), counted as bytes read plus
// bytes written. The force kernel's bytes_per_s is compared with this in docs/performance.md.
#include <benchmark/benchmark.h>

#include <cstring>
#include <vector>

namespace {

void BM_MemoryCopy(benchmark::State& state) {
  const std::size_t bytes = static_cast<std::size_t>(state.range(0)) << 20;
  std::vector<char> from(bytes, 1), to(bytes, 0);
  for (auto _ : state) {
    std::memcpy(to.data(), from.data(), bytes);
    benchmark::ClobberMemory();
  }
  state.counters["bytes_per_s"] =
      benchmark::Counter(2.0 * static_cast<double>(bytes), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_MemoryCopy)->Arg(256)->ArgName("MiB")->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
