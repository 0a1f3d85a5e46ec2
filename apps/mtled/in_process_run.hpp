#pragma once
// A scene run in the calling process as `mtled run` runs it (SceneRun, scene_run.hpp), kept whole after the run so that
// its results are read where they lie: the simulation's final state and its summary. The Python module's runs and a
// fit's forward runs.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "mtled/analysis/fit.hpp"
#include "mtled/scene.hpp"
#include "scene_run.hpp"

namespace mtled::app {

// A scene as read and edited: the document, and the assignments made to it (summary.json's "overrides": Python's set(),
// a fit's parameters).
struct SceneText {
  SceneDocument document;
  std::vector<std::string> assignments;  // "/pointer=value", as --set
};

struct RunRequest {
  std::filesystem::path output;  // the run's folder (cleared of an earlier run's files)
  int threads = 0;               // 0: as mtled run (OMP_NUM_THREADS when set, else every core)
  std::vector<std::filesystem::path> plugin_paths;
  std::vector<std::shared_ptr<StepMonitor>> observers;  // called after every step, after the scene's writers
  BasisCache* bases = nullptr;  // the meshless bases runs of one mesh share (null: the run builds its own)
};

class InProcessRun {
 public:
  // Validates the scene (InputError with every problem, nothing written) and runs it to its end; any outcome but an
  // invalid input or a failure is status().
  InProcessRun(const SceneText& scene, const RunRequest& request);
  InProcessRun(const InProcessRun&) = delete;
  InProcessRun& operator=(const InProcessRun&) = delete;
  ~InProcessRun();

  // summary.json's status: "ok", "unstable", "stopped", "interrupted" or "timeout"; the exit code `mtled run` gives.
  std::string status() const;
  int exit_code() const { return exit_code_; }
  const SceneRun& run() const { return *run_; }
  const Simulation& simulation() const { return *run_->simulation(); }

 private:
  PluginCatalog catalog_;  // first: the plugins' libraries outlive the objects they made
  Scene scene_;
  std::unique_ptr<SceneRun> run_;
  int exit_code_ = 0;
};

// Every problem validating the scene finds, each located in it (none: valid), as `mtled validate` reports them.
std::vector<Problem> scene_problems(const SceneDocument& document,
                                    const std::vector<std::filesystem::path>& plugin_paths);

// A fit's forward run in this process, as a child `mtled run` does it: its log in its folder (mtled.log), stopped with
// status "timeout" after run.timeout_s, the meshless basis of each mesh built once and shared through `bases` (null:
// the run builds its own). How it ended, exit_code as `mtled run`'s (2: invalid input).
RunOutcome run_forward_in_process(const fit::ForwardRun& run, BasisCache* bases);

}  // namespace mtled::app
