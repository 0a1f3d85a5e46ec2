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
#include "progress.hpp"
#include "scene_run.hpp"

namespace mtled::app {

namespace {

std::atomic<bool> interrupted{false};
extern "C" void on_interrupt(int) { interrupted = true; }

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

int run_thread_count(int requested) {
  if (requested > 0) return requested;
  if (std::getenv("OMP_NUM_THREADS")) return omp_get_max_threads();
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

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
  const int threads = run_thread_count(options.threads);
  omp_set_num_threads(threads);
  if (!processes().writes()) return replica_run(scene, catalog);
  SceneRun run(options, scene, catalog, threads, wall_start);
  std::vector<std::shared_ptr<StepMonitor>> observers;
  if (auto failure = injected_failure()) observers.push_back(failure);
  observers.push_back(std::make_shared<ProgressWriter>(options.progress, interrupted));
  return run.run(observers);
}

}  // namespace mtled::app
