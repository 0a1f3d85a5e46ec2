// mtled study: runs a scene under several settings against a reference and reports error against run time
// (the study library, analysis/include/mtled/analysis/study.hpp; the file format in docs/studies.md). Under mpirun
// each rank runs its share of the configurations and rank 0 measures and reports; --job-list writes the runs as
// command lines for a batch scheduler instead, and --gather reports on the runs those made.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>

#include "commands.hpp"
#include "mtled/analysis/study.hpp"
#include "mtled/errors.hpp"
#include "mtled/log.hpp"
#include "processes.hpp"

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

std::string counter(std::size_t i, std::size_t n) { return fmt::format("[{}/{}]", i + 1, n); }

// One command line per run, the reference's first.
int write_job_list(const study::Study& plan, const study::Runner& runner, const std::filesystem::path& file) {
  std::ofstream out(file);
  if (!out) throw InputError(file.string(), "cannot write the job list here: choose a writable path for --job-list");
  std::size_t lines = 0;
  if (plan.reference.kind == study::Reference::Kind::configuration) {
    out << runner.command_line(plan.reference.configuration) << "\n";
    ++lines;
  }
  for (const auto& c : plan.configurations) {
    out << runner.command_line(c) << "\n";
    ++lines;
  }
  log().info("wrote {} run commands to {}; when they have run: mtled study {} -o FOLDER --gather", lines, file.string(),
             plan.file.string());
  return 0;
}

// Every rank executes the configurations i with i mod ranks = its rank; rank 0 gets every outcome.
std::vector<study::RunOutcome> execute_shares(const study::Study& plan, study::Runner& runner) {
  ProcessGroup& group = processes();
  const std::size_t n = plan.configurations.size();
  constexpr std::size_t kFields = 6;
  std::vector<double> packed(kFields * n, 0.0);
  for (std::size_t i = static_cast<std::size_t>(group.rank()); i < n; i += static_cast<std::size_t>(group.size())) {
    const study::RunOutcome o = runner.execute(plan.configurations[i], counter(i, n));
    const double fields[kFields] = {o.reused ? 1.0 : 0.0, static_cast<double>(o.exit_code), static_cast<double>(o.signal),
                                    o.timed_out ? 1.0 : 0.0, o.elapsed_s, o.max_rss_mb};
    std::copy(fields, fields + kFields, packed.begin() + static_cast<std::ptrdiff_t>(kFields * i));
  }
  group.sum_on_first(packed);  // each entry is one rank's alone: the sum gathers them
  std::vector<study::RunOutcome> outcomes(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double* f = packed.data() + kFields * i;
    outcomes[i] = {f[0] != 0.0, static_cast<int>(f[1]), static_cast<int>(f[2]), f[3] != 0.0, f[4], f[5]};
  }
  return outcomes;
}

}  // namespace

int study_command(const StudyOptions& options) {
  study::Study plan = study::read(options.study);
  study::check_scenes(plan, options.plugin_paths);
  const study::Settings settings{options.plugin_paths, options.threads, options.reuse, options.log_level, options.gather};
  study::Runner runner(plan, settings, options.output);
  if (!options.job_list.empty()) return processes().writes() ? write_job_list(plan, runner, options.job_list) : 0;
  if (options.gather && processes().size() > 1)
    throw InputError("--gather", "gathering reads files and runs nothing: run it without mpirun");
  const auto start = std::chrono::steady_clock::now();

  // Rank 0 makes the folder and runs the reference; the others start their shares when it is there.
  std::unique_ptr<OutputFolder> out;
  study::ReferenceResult reference;
  if (processes().writes()) {
    out = std::make_unique<OutputFolder>(options.output);
    std::filesystem::create_directories(out->path() / "runs");
    reference = study::establish_reference(plan, runner);
  }
  processes().barrier();
  std::vector<study::RunOutcome> outcomes;
  if (options.gather)
    for (const auto& c : plan.configurations) outcomes.push_back(runner.outcome_from_folder(c));
  else
    outcomes = execute_shares(plan, runner);
  if (!processes().writes()) return 0;

  const study::Measure measure(plan, reference, options.plugin_paths);
  std::vector<study::Row> rows;
  for (std::size_t i = 0; i < plan.configurations.size(); ++i) {
    const study::Configuration& c = plan.configurations[i];
    study::Row row = runner.record(c, outcomes[i]);
    measure(row, runner.folder(c));
    print_outcome(counter(i, plan.configurations.size()), row, plan);
    rows.push_back(std::move(row));
  }
  study::mark_pareto(rows);

  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const int threads = options.threads > 0 ? options.threads : plan.threads;
  study::write_reports(*out, plan, reference, rows, threads, seconds);
  study::print_table(std::cout, plan, rows, out->path(), seconds);
  const bool any_ok = std::any_of(rows.begin(), rows.end(), [](const study::Row& r) { return r.status == "ok"; });
  if (!any_ok) log().error("no configuration of the study succeeded");
  return any_ok ? 0 : 1;
}

}  // namespace mtled::app
