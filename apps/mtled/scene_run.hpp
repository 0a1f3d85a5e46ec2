#pragma once
// One `mtled run` on the process that writes: the output folder (cleared of an earlier run's files), its summary, the
// simulation with its monitors and writers, and the outcome recorded (summary.json last, so that it always says how
// the run ended).
#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mtled/io/run_outputs.hpp"
#include "mtled/monitors/scene_monitors.hpp"

namespace mtled::app {

class SceneRun {
 public:
  using Clock = std::chrono::steady_clock;
  // `wall_start`: before the scene was read; `threads`: the run's thread count, already set.
  SceneRun(const RunOptions& options, const Scene& scene, PluginCatalog& catalog, int threads,
           Clock::time_point wall_start);

  // The exit code: 0 with result.vtu, 1 interrupted, 3 unstable (last_good_state.vtu). An invalid input is rethrown at
  // its scene line, any other failure as it came, each after summary.json recorded it.
  int run(bool progress, const std::atomic<bool>& interrupted);

 private:
  void record(double solve_time);
  int unstable(const InstabilityError& e);
  int finish_without_result(const std::string& status, double solve_time, const std::string& error);
  void check_displacement_field() const;
  void write_displacement_field() const;
  int succeeded(double solve_time);

  const Clock::time_point wall_start_;
  const Scene& scene_;
  PluginCatalog& catalog_;
  const std::vector<std::filesystem::path> plugin_paths_;
  const OutputFolder folder_;
  RunSummary summary_;
  Clock::time_point solve_start_ = Clock::now();
  double setup_time_ = 0.0;
  std::unique_ptr<Simulation> simulation_;
  std::shared_ptr<const FoldedTets> folded_;  // marked by the inversion check when it stops the run
  std::vector<std::shared_ptr<OutputWriter>> writers_;
};

}  // namespace mtled::app
