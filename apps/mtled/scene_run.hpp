#pragma once
// One `mtled run` on the process that writes: the output folder (cleared of an earlier run's files), its summary, the
// simulation with its monitors and writers, and the outcome recorded (summary.json last, so that it always says how
// the run ended). The command line and the Python module (python/) both run a scene through it.
#include <chrono>
#include <filesystem>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mtled/io/run_outputs.hpp"
#include "mtled/monitors/scene_monitors.hpp"

namespace mtled::app {

// Thrown by an observer to end a run early without a result: summary.json records `status` ("interrupted" on Ctrl-C,
// "stopped" when a Python callback asked for it) and the exit code is 1.
struct RunStopped : std::runtime_error {
  RunStopped(std::string stopped_status, const std::string& why)
      : std::runtime_error(why), status(std::move(stopped_status)) {}
  std::string status;
};

class SceneRun {
 public:
  using Clock = std::chrono::steady_clock;
  // `wall_start`: before the scene was read; `threads`: the run's thread count, already set; `bases`: the meshless
  // bases runs of the same mesh share (MechanicalSystem; null: this run builds its own).
  SceneRun(const RunOptions& options, const Scene& scene, PluginCatalog& catalog, int threads,
           Clock::time_point wall_start, BasisCache* bases = nullptr);

  // The exit code: 0 with result.vtu, 1 stopped (RunStopped), 3 unstable (last_good_state.vtu). An invalid input is
  // rethrown at its scene line, any other failure as it came, each after summary.json recorded it. `observers` watch
  // every step after the scene's own monitors and writers (the terminal's progress, a Python callback); one that is
  // an OutputWriter is finished like the writers when the run stops unstable.
  int run(const std::vector<std::shared_ptr<StepMonitor>>& observers);

  // After run(): the simulation in its final state (null when setting it up failed), summary.json as written, the
  // interpolated displacement of the state the run wrote, result.vtu or last_good_state.vtu (3 per node; empty when it
  // wrote neither), and that state's nodal parameters u_I (the simulation's; empty likewise), from which the field is
  // read anywhere (field_at).
  const Simulation* simulation() const { return simulation_.get(); }
  const json& summary() const { return summary_.contents(); }
  std::span<const double> written_displacement() const { return written_displacement_; }
  std::span<const double> written_state() const { return written_state_; }
  const std::filesystem::path& folder() const { return folder_.path(); }

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
  BasisCache* const bases_;
  const std::vector<std::filesystem::path> plugin_paths_;
  const OutputFolder folder_;
  RunSummary summary_;
  Clock::time_point solve_start_ = Clock::now();
  double setup_time_ = 0.0;
  std::unique_ptr<Simulation> simulation_;
  std::shared_ptr<const FoldedTets> folded_;  // marked by the inversion check when it stops the run
  std::vector<std::shared_ptr<OutputWriter>> writers_;
  std::vector<double> written_displacement_;
  std::span<const double> written_state_;
};

}  // namespace mtled::app
