// mtled fit: scene parameters identified from measurements (the fit library, analysis/include/mtled/analysis/fit.hpp;
// the file format in docs/calibration.md). Everything is checked before the first forward run; with --synthesize the
// command writes data made by the model at the start values, with seeded noise, instead of fitting.
#include <fmt/ranges.h>

#include <iostream>

#include "commands.hpp"
#include "in_process_run.hpp"
#include "mtled/analysis/fit.hpp"
#include "mtled/io/output.hpp"
#include "mtled/log.hpp"

namespace mtled::app {

namespace {

// Ends a run that has gone on longer than its limit, as the timeout of a child run does.
class WallClockLimit final : public StepMonitor {
 public:
  WallClockLimit(SceneRun::Clock::time_point start, double limit_s) : start_(start), limit_s_(limit_s) {}
  std::string name() const override { return "wall_clock_limit"; }
  void after_step(const StepRecord&) override {
    if (std::chrono::duration<double>(SceneRun::Clock::now() - start_).count() > limit_s_)
      throw RunStopped("timeout", fmt::format("still running after the fit's timeout_s, {:g} s", limit_s_));
  }
  bool reads_displacement(long) const override { return false; }

 private:
  SceneRun::Clock::time_point start_;
  double limit_s_;
};

}  // namespace

RunOutcome run_forward_in_process(const fit::ForwardRun& run, BasisCache* bases) {
  const auto start = SceneRun::Clock::now();
  RunOutcome outcome;
  {
    const ThreadLogFile log_file(run.folder / "mtled.log", run.log_level);
    try {
      RunRequest request{run.folder, run.threads, run.plugin_paths, {}, bases};
      if (run.timeout_s > 0.0) request.observers.push_back(std::make_shared<WallClockLimit>(start, run.timeout_s));
      const InProcessRun done({read_scene(run.scene, run.assignments), run.assignments}, request);
      outcome.exit_code = done.exit_code();
      outcome.timed_out = done.status() == "timeout";
    } catch (const InputError& e) {
      log().error("{}", e.what());
      outcome.exit_code = 2;
    } catch (const std::exception& e) {
      log().error("{}", e.what());
      outcome.exit_code = 1;
    }
  }
  outcome.elapsed_s = std::chrono::duration<double>(SceneRun::Clock::now() - start).count();
  return outcome;
}

int fit_command(const FitOptions& options) {
  fit::Plan plan = fit::read(options.fit, options.overrides, options.plugin_paths);
  if (options.check) {  // everything read and checked; a template for --synthesize passes
    log().info("{}: {} parameters, {} experiments: ready to run", options.fit.string(), plan.parameters.size(),
               plan.experiments.size());
    return 0;
  }
  if (options.threads > 0) plan.settings.threads = options.threads;
  const OutputFolder out(options.output);
  if (!options.synthesize) fit::check_measured(plan);  // a template for --synthesize may lack measured values
  const double mesh_seconds =
      options.reuse_mesh ? fit::write_meshes_once(plan, out.path(), options.plugin_paths) : 0.0;
  // The forward runs go in this process, each experiment's meshless basis built by its first run (a launcher sends
  // them elsewhere instead, as child processes).
  BasisCache bases;
  fit::InProcessRunner in_process = [shared = options.reuse_mesh ? &bases : nullptr](const fit::ForwardRun& run) {
    return run_forward_in_process(run, shared);  // --no-mesh-reuse: each run builds its own
  };
  fit::Evaluator evaluator(plan, out.path(), options.plugin_paths, options.log_level, in_process);
  std::size_t data = 0;
  for (const auto& e : plan.experiments) data += e.data.size();
  const std::vector<std::string>& launcher = plan.settings.launcher;
  log().info("fit: {} parameters, {} experiments, {} data; up to {} runs at once {}", plan.parameters.size(),
             plan.experiments.size(), data, evaluator.runs_at_once(),
             launcher.empty() ? fmt::format("sharing {} threads", evaluator.threads())
                              : fmt::format("through `{}`, {} threads each", fmt::join(launcher, " "),
                                            evaluator.threads()));
  if (options.synthesize) {
    fit::synthesize(plan, evaluator, *options.synthesize, out.path() / "data");
    return 0;
  }
  fit::Result result = fit::solve(plan, evaluator);
  result.setup_seconds = mesh_seconds;
  const fit::Statistics stats = fit::statistics(plan, result);
  fit::write_report(plan, result, stats, out.path());
  fit::print_summary(std::cout, plan, result, stats);
  if (result.values.empty()) {
    log().error("the fit failed: {}", result.termination);
    return 1;
  }
  return 0;
}

}  // namespace mtled::app
