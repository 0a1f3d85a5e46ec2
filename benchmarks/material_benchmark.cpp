// Second Piola-Kirchhoff stress of every registered material for a moderately strained F (the per-
// integration-point constitutive cost inside the force kernel), one point at a time and in the batches the
// kernel uses.
#include <benchmark/benchmark.h>

#include <cstdlib>

#include "mtled/interfaces/material.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/simd.hpp"

namespace {

using namespace mtled;

PluginCatalog& catalog() {
  static PluginCatalog c(plugin_search_path({}, {}));
  return c;
}

std::shared_ptr<Material> material(const std::string& name) {
  const ComponentDeclaration& declaration = catalog().load(Category::material, name);
  json block = {{"mu", 722.0}, {"D", 5.57738e-5}, {"density", 1000.0}};
  if (name == "ogden") block["alpha"] = -1.3;
  std::vector<Problem> problems;
  const Parameters p = validate_parameters(declaration, block, "/benchmark", problems, {"type"});
  if (!problems.empty()) throw std::runtime_error(problems.front().format());
  return catalog().create<Material>(name, p);
}

void BM_MaterialStress(benchmark::State& state, const std::string& name) {
  const auto m = material(name);
  Mat3 F;
  F << 1.05, 0.02, -0.01, 0.01, 0.97, 0.03, -0.02, 0.01, 0.99;
  Mat3 S;
  for (auto _ : state) {
    benchmark::DoNotOptimize(F);
    benchmark::DoNotOptimize(m->stress(F, S));
    benchmark::DoNotOptimize(S);
  }
  state.counters["stresses_per_s"] = benchmark::Counter(1.0, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK_CAPTURE(BM_MaterialStress, neo_hookean, std::string("neo_hookean"));
BENCHMARK_CAPTURE(BM_MaterialStress, ogden, std::string("ogden"));

// The same F in every lane of a full batch (what the force kernel calls); the time is per point.
void BM_MaterialStressBatch(benchmark::State& state, const std::string& name) {
  // MTLED_SIMD=avx2 (or sse4, baseline, ...) times another instruction set than the CPU's best.
  if (const char* simd = std::getenv("MTLED_SIMD")) simd::use(simd);
  const auto m = material(name);
  Mat3 F;
  F << 1.05, 0.02, -0.01, 0.01, 0.97, 0.03, -0.02, 0.01, 0.99;
  StressBatch batch;
  batch.count = StressBatch::kCapacity;
  for (int p = 0; p < batch.count; ++p)
    for (int c = 0; c < 9; ++c) batch.F[c][p] = F(c / 3, c % 3);
  for (auto _ : state) {
    benchmark::DoNotOptimize(batch.F);
    m->stress_batch(batch);
    benchmark::DoNotOptimize(batch.S);
  }
  state.SetItemsProcessed(state.iterations() * batch.count);
  state.counters["ns_per_point"] = benchmark::Counter(static_cast<double>(batch.count),
                                                      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK_CAPTURE(BM_MaterialStressBatch, neo_hookean, std::string("neo_hookean"));
BENCHMARK_CAPTURE(BM_MaterialStressBatch, ogden, std::string("ogden"));

}  // namespace
