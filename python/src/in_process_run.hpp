#pragma once
// A scene run in the calling process as `mtled run` runs it (SceneRun, apps/mtled/scene_run.hpp), kept whole after the
// run so that its results are read where they lie: the simulation's final state and its summary.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "mtled/scene.hpp"
#include "scene_run.hpp"

namespace mtled::python {

// A scene as Python edits it: the document, and the assignments set() made (summary.json's "overrides").
struct SceneText {
  SceneDocument document;
  std::vector<std::string> assignments;  // "/pointer=value", as --set
};

struct RunRequest {
  std::filesystem::path output;  // the run's folder (cleared of an earlier run's files)
  int threads = 0;               // 0: as mtled run (OMP_NUM_THREADS when set, else every core)
  std::vector<std::filesystem::path> plugin_paths;
  std::vector<std::shared_ptr<StepMonitor>> observers;  // called after every step, after the scene's writers
};

class InProcessRun {
 public:
  // Validates the scene (InputError with every problem, nothing written) and runs it to its end; any outcome but an
  // invalid input or a failure is status().
  InProcessRun(const SceneText& scene, const RunRequest& request);
  InProcessRun(const InProcessRun&) = delete;
  InProcessRun& operator=(const InProcessRun&) = delete;
  ~InProcessRun();

  // summary.json's status: "ok", "unstable", "stopped" or "interrupted".
  std::string status() const;
  const app::SceneRun& run() const { return *run_; }
  const Simulation& simulation() const { return *run_->simulation(); }

 private:
  PluginCatalog catalog_;  // first: the plugins' libraries outlive the objects they made
  Scene scene_;
  std::unique_ptr<app::SceneRun> run_;
};

// Every problem validating the scene finds, each located in it (none: valid), as `mtled validate` reports them.
std::vector<Problem> scene_problems(const SceneDocument& document,
                                    const std::vector<std::filesystem::path>& plugin_paths);

}  // namespace mtled::python
