// The internal-force kernel (ForceKernel::internal_forces) on the default scene's cloud (the paper's coarse grid of
// the small sample, about 7,500 nodes and 38,000 integration points), for 1 and 2 threads. Counters:
// integration-point updates per second and the kernel's memory traffic per second, counted as the bytes the
// kernel must move once per call (ForceKernel::streamed_bytes_per_force_evaluation). At the end, the constraint
// projection of that cloud's fixed face.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdlib>
#include <map>
#include <memory>
#include <random>

#include "mtled/analysis/scene_sections.hpp"
#include "mtled/constraints.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/scene.hpp"
#include "mtled/simd.hpp"
#include "mtled/simulation.hpp"

namespace {

using namespace mtled;

struct Setup {
  std::unique_ptr<PluginCatalog> catalog;
  std::unique_ptr<Simulation> simulation;
};

// One simulation per thread count and row precision: the model sizes its thread team when it is built.
Simulation& simulation_for(int threads, const std::string& precision) {
  static std::map<std::pair<int, std::string>, Setup> setups;
  auto& s = setups[{threads, precision}];
  if (!s.simulation) {
    // MTLED_SIMD=avx2 (or sse4, baseline, ...) times another instruction set than the CPU's best.
    if (const char* simd = std::getenv("MTLED_SIMD")) simd::use(simd);
    omp_set_num_threads(threads);
    SceneDocument document = read_scene(MTLED_SOURCE_DIR "/share/scenes/needle_small_sample.json");
    document.root["discretisation"]["precision"] = precision;
    s.catalog = std::make_unique<PluginCatalog>(plugin_search_path({}, scene_plugin_paths(document)));
    const Scene scene = validate_scene(std::move(document), *s.catalog, run_scene_sections());  // its "output" too
    s.simulation = std::make_unique<Simulation>(scene, *s.catalog);
  }
  return *s.simulation;
}

void internal_forces(benchmark::State& state, const std::string& precision) {
  const int threads = static_cast<int>(state.range(0));
  Simulation& simulation = simulation_for(threads, precision);
  const Discretisation& model = simulation.system().discretisation();
  const ForceKernel& kernel = simulation.system().force_kernel();
  const std::size_t dofs = 3 * static_cast<std::size_t>(model.node_count());
  // A smooth field of about 1% strain: every integration point does real work.
  std::vector<double> u(dofs), f(dofs);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> noise(-1e-6, 1e-6);
  for (Index i = 0; i < model.node_count(); ++i)
    for (int k = 0; k < 3; ++k) u[3 * i + k] = 0.01 * model.nodes()[i][k] * (k == 2 ? -1.0 : 0.5) + noise(random);
  for (auto _ : state) {
    benchmark::DoNotOptimize(kernel.internal_forces(u, f));
    benchmark::ClobberMemory();
  }
  const double entries = static_cast<double>(model.gradients().entries());
  const double ips = static_cast<double>(model.points().count());
  const auto bytes = static_cast<double>(kernel.streamed_bytes_per_force_evaluation());
  state.counters["ip_updates_per_s"] = benchmark::Counter(ips, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["bytes_per_s"] = benchmark::Counter(bytes, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["support_mean"] = entries / ips;
  state.counters["integration_points"] = ips;
  state.SetLabel(simd::current());
}
void BM_InternalForces(benchmark::State& state) { internal_forces(state, "double"); }
BENCHMARK(BM_InternalForces)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();

// Gradients stored in single precision (/discretisation/precision "single"): half the rows' bytes.
void BM_InternalForcesSingle(benchmark::State& state) { internal_forces(state, "single"); }
BENCHMARK(BM_InternalForcesSingle)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();

// The same on the portable baseline instruction set (no SIMD): what the vectorisation gives.
void BM_InternalForcesBaseline(benchmark::State& state) {
  simd::use("baseline");
  internal_forces(state, "double");
  simd::use("best");
}
BENCHMARK(BM_InternalForcesBaseline)->Arg(1)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();

// The constraint projection (ConstraintSystem::enforce) of the default scene's fixed bottom face, all three
// components: Phi u, the solves with the factor of Phi M^-1 Phi^T, and u += M^-1 Phi^T y, as every time step does. In
// this loop the factor stays in the caches, as it does on a GPU backend's host; in a CPU run the force kernel's
// stream evicts it between steps.
void BM_ConstraintProjection(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const Discretisation& model = simulation_for(threads, "single").system().discretisation();
  NodalConstraints bottom;  // the scene's fixed boundary, without the needle's driven nodes
  bottom.name = "bottom";
  for (const Index node : model.mesh().node_sets.at("bottom")) bottom.add_node(node, Vec3::Zero());
  ConstraintSystem constraints(model);
  constraints.update({&bottom}, model.lumped_mass(), true);
  std::vector<double> u(3 * static_cast<std::size_t>(model.node_count()));
  std::mt19937 random(5);
  std::uniform_real_distribution<double> noise(-1e-6, 1e-6);
  for (double& value : u) value = noise(random);
  for (auto _ : state) {
    constraints.enforce(u, 1.0);
    benchmark::ClobberMemory();
  }
  state.counters["rows"] = static_cast<double>(bottom.size());
}
BENCHMARK(BM_ConstraintProjection)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace
