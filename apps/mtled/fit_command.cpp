// mtled fit: scene parameters identified from measurements (the fit library, analysis/include/mtled/analysis/fit.hpp;
// the file format in docs/calibration.md). Everything is checked before the first forward run; with --synthesize the
// command writes data made by the model at the start values, with seeded noise, instead of fitting.
#include <fmt/ranges.h>

#include <iostream>

#include "commands.hpp"
#include "mtled/analysis/fit.hpp"
#include "mtled/io/output.hpp"
#include "mtled/log.hpp"

namespace mtled::app {

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
  fit::Evaluator evaluator(plan, out.path(), options.plugin_paths, options.log_level);
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
