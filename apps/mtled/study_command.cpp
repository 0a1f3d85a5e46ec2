// mtled study: runs a scene under several settings against a reference and reports error against run time
// (the study library, analysis/include/mtled/analysis/study.hpp; the file format in docs/studies.md).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <iostream>

#include "commands.hpp"
#include "mtled/analysis/study.hpp"
#include "mtled/log.hpp"

namespace mtled::app {

namespace {

void print_outcome(const std::string& counter, const study::Row& r, const study::Study& plan) {
  if (r.status == "ok")
    fmt::print(stderr, "study {} {}: ok, wall {:.3g} s, {} {:.4g}\n", counter, r.configuration->label, r.wall_s,
               plan.metric.name, r.error);
  else
    fmt::print(stderr, "study {} {}: {} (exit {}){}\n", counter, r.configuration->label, r.status, r.exit_code,
               r.message.empty() ? "" : ": " + r.message);
}

}  // namespace

int study_command(const StudyOptions& options) {
  study::Study plan = study::read(options.study);
  study::check_scenes(plan, options.plugin_paths);
  const OutputFolder out(options.output);
  std::filesystem::create_directories(out.path() / "runs");
  const study::Settings settings{options.plugin_paths, options.threads, options.reuse, options.log_level};
  const auto start = std::chrono::steady_clock::now();

  study::Runner runner(plan, settings, out.path());
  const study::ReferenceResult reference = study::establish_reference(plan, runner);
  const study::Measure measure(plan, reference, options.plugin_paths);
  std::vector<study::Row> rows;
  for (std::size_t i = 0; i < plan.configurations.size(); ++i) {
    const study::Configuration& c = plan.configurations[i];
    const std::string counter = fmt::format("[{}/{}]", i + 1, plan.configurations.size());
    study::Row row = runner.run(c, counter);
    measure(row, runner.folder(c));
    print_outcome(counter, row, plan);
    rows.push_back(std::move(row));
  }
  study::mark_pareto(rows);

  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  study::write_reports(out, plan, reference, rows, options.threads > 0 ? options.threads : plan.threads, seconds);
  study::print_table(std::cout, plan, rows, out.path(), seconds);
  const bool any_ok = std::any_of(rows.begin(), rows.end(), [](const study::Row& r) { return r.status == "ok"; });
  if (!any_ok) log().error("no configuration of the study succeeded");
  return any_ok ? 0 : 1;
}

}  // namespace mtled::app
