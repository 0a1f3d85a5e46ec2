// mtled run: read and validate the scene (on a group of processes, for the group's backend), then run it: the process
// that writes through a SceneRun (scene_run.hpp), the others as replicas that take part in every exchange.
#include <omp.h>

#include <atomic>
#include <csignal>
#include <cstdlib>
#include <thread>

#include "commands.hpp"
#include "mtled/analysis/scene_sections.hpp"
#include "mtled/monitors/scene_monitors.hpp"
#include "processes.hpp"
#include "scene_run.hpp"

namespace mtled::app {

namespace {

std::atomic<bool> interrupted{false};
extern "C" void on_interrupt(int) { interrupted = true; }

// --threads, else OMP_NUM_THREADS when set (the OpenMP convention), else every core.
int thread_count(const RunOptions& options) {
  if (options.threads > 0) return options.threads;
  if (std::getenv("OMP_NUM_THREADS")) return omp_get_max_threads();
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// A rank other than 0: the same simulation and checks, which take part in every exchange of forces; no files.
int replica_run(const Scene& scene, PluginCatalog& catalog) {
  Simulation simulation(scene, catalog);
  add_scene_monitors(simulation, scene);
  if (auto failure = injected_failure()) simulation.loop().add_monitor(failure);
  try {
    simulation.loop().run();
  } catch (const InstabilityError&) {
    return 3;  // rank 0 reports it
  }
  return 0;
}

}  // namespace

int run_scene(const RunOptions& options) {
  const auto wall_start = SceneRun::Clock::now();
  SceneDocument document = read_scene(options.scene.scene, options.scene.overrides);
  run_across(document, processes());
  PluginCatalog catalog(plugin_search_path(options.scene.plugin_paths, scene_plugin_paths(document)));
  const Scene scene = validate_scene(std::move(document), catalog, run_scene_sections());
  // On every rank: under mpirun Ctrl-C reaches each rank, and the others keep computing until rank 0 has finished
  // its step and written "interrupted" (then the launcher ends them).
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  const int threads = thread_count(options);
  omp_set_num_threads(threads);
  if (!processes().writes()) return replica_run(scene, catalog);
  SceneRun run(options, scene, catalog, threads, wall_start);
  return run.run(options.progress, interrupted);
}

}  // namespace mtled::app
