#include "in_process_run.hpp"

#include <omp.h>

#include "commands.hpp"
#include "mtled/analysis/scene_sections.hpp"

namespace mtled::app {

namespace {

PluginCatalog scene_catalog(const SceneDocument& document, const std::vector<std::filesystem::path>& plugin_paths) {
  return PluginCatalog(plugin_search_path(plugin_paths, scene_plugin_paths(document)));
}

}  // namespace

InProcessRun::InProcessRun(const SceneText& scene, const RunRequest& request)
    : catalog_(scene_catalog(scene.document, request.plugin_paths)),
      scene_(validate_scene(scene.document, catalog_, run_scene_sections())) {
  const auto wall_start = SceneRun::Clock::now();
  RunOptions options;
  options.scene.scene = scene.document.file.empty() ? std::filesystem::path(scene.document.name) : scene.document.file;
  options.scene.overrides = scene.assignments;
  options.scene.plugin_paths = request.plugin_paths;
  options.output = request.output;
  options.threads = run_thread_count(request.threads);
  options.progress = false;
  omp_set_num_threads(options.threads);  // this thread's (a run on another thread sets its own)
  run_ = std::make_unique<SceneRun>(options, scene_, catalog_, options.threads, wall_start, request.bases);
  exit_code_ = run_->run(request.observers);
}

InProcessRun::~InProcessRun() = default;

std::string InProcessRun::status() const { return run_->summary().value("status", ""); }

std::vector<Problem> scene_problems(const SceneDocument& document,
                                    const std::vector<std::filesystem::path>& plugin_paths) {
  try {
    PluginCatalog catalog = scene_catalog(document, plugin_paths);
    validate_scene(document, catalog, run_scene_sections());
  } catch (const InputError& e) {
    return e.problems();
  }
  return {};
}

}  // namespace mtled::app
