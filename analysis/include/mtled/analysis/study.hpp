#pragma once
// A study (`mtled study`, docs/studies.md): a scene run under several settings (a list of configurations and/or
// a cartesian sweep), each measured against a reference with a named metric, reported as error against run
// time. Four parts, one file each:
//   plan      (study_plan.cpp)     read the study file, check every configuration's scene before anything runs;
//   runs      (study_runs.cpp)     run a configuration as a child `mtled run` process (a run that fails, crashes
//                                  or times out is recorded and the study goes on), or reuse an earlier one;
//   metrics   (study_metrics.cpp)  establish the reference, measure each run against it, the Pareto front;
//   report    (study_report.cpp)   study.csv, study.json, error_vs_time.svg and the table on the terminal.
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "mtled/analysis/child_run.hpp"
#include "mtled/json.hpp"
#include "mtled/io/output.hpp"
#include "mtled/types.hpp"

namespace mtled {
class PluginCatalog;
}

namespace mtled::study {

struct Configuration {
  std::string label;
  std::string folder;                     // folder name under runs/
  std::string where;                      // its place in the study file, for messages
  json set = json::object();              // JSON pointer -> value: the study's common "set", then its own
  std::vector<std::string> overrides;     // the --set arguments
  json settings = json::object();         // value of every varied pointer in the scene as run ("default" if absent)
  std::optional<double> reference_value;  // its own exact value, for value metrics (a material sweep)
};

enum class MetricKind { nrmse, force_error, summary_error };

struct Metric {
  MetricKind kind = MetricKind::nrmse;
  std::string pointer;   // force_error, summary_error: JSON pointer of the quantity in summary.json
  int component = -1;    // nrmse: -1 for the largest of x, y, z; else 0, 1, 2
  std::string name;      // "nrmse", "force_error", "summary_error"
  std::string describe;  // axis label
};

struct Reference {
  enum class Kind { value, run, configuration } kind = Kind::value;
  double value = 0.0;
  std::filesystem::path run;  // Kind::run: the folder
  Configuration configuration;  // Kind::configuration: run first, into runs/
};

struct Study {
  std::filesystem::path file, scene;
  std::string description;
  std::vector<Configuration> configurations;
  std::vector<std::string> varied;  // pointers set anywhere, in order of first appearance
  Metric metric;
  Reference reference;
  int threads = 0;
  double timeout_s = 0.0;
};

// One configuration's run and its measurement.
struct Row {
  const Configuration* configuration = nullptr;
  std::string status;
  int exit_code = -1;
  bool reused = false;
  json summary;
  double setup_s = NAN, solve_s = NAN, wall_s = NAN, peak_mb = NAN;
  long steps = -1, nodes = -1, integration_points = -1;
  double value = NAN;      // force_error, summary_error: the quantity
  double reference = NAN;  // ... and the value it is measured against
  Vec3 nrmse = Vec3::Constant(NAN);
  double error = NAN;
  bool pareto = false;
  std::string message;  // why it failed, in full (study.json)
  std::string note;     // the same in a few words (the plot)
};

// What the command line passes on to every run.
struct Settings {
  std::vector<std::filesystem::path> plugin_paths;
  int threads = 0;  // 0: the study file's "threads", else the run's default
  bool reuse = false;
  std::string log_level = "info";
  bool gather = false;  // run nothing: read every run from its folder (runs a batch scheduler made)
};

// ---- plan
// Reads and checks the study file; InputError with every problem, each naming the file and JSON pointer.
Study read(const std::filesystem::path& file);
// Checks every configuration's scene (and the reference's) as `mtled validate` would; fills their overrides
// and the settings of the varied pointers.
void check_scenes(Study& study, const std::vector<std::filesystem::path>& plugin_paths);

// ---- runs
using mtled::RunOutcome;  // how a run's process ended (child_run.hpp)

class Runner {
 public:
  Runner(const Study& study, const Settings& settings, const std::filesystem::path& output);
  // Runs one configuration (or, with reuse, keeps its earlier successful run) and reads its summary: execute, then
  // record. A study spread over processes executes on each and records on one.
  Row run(const Configuration& configuration, const std::string& counter);
  RunOutcome execute(const Configuration& configuration, const std::string& counter);
  Row record(const Configuration& configuration, const RunOutcome& outcome) const;
  // The configuration's run as one shell command line (a batch scheduler's job; its log in the run's folder).
  std::string command_line(const Configuration& configuration) const;
  // The outcome of a run a scheduler made, read from its folder's summary.json (no summary: failed).
  RunOutcome outcome_from_folder(const Configuration& configuration) const;
  std::filesystem::path folder(const Configuration& configuration) const { return runs_ / configuration.folder; }

 private:
  Row reused(const Configuration& configuration, const std::string& counter) const;
  std::vector<std::string> arguments(const Configuration& configuration) const;

  const Study& study_;
  const Settings& settings_;
  std::filesystem::path runs_, executable_;
  int threads_ = 0;
};

// ---- metrics
struct ReferenceResult {
  std::filesystem::path folder;  // the reference run's folder (empty for an exact value)
  double value = 0.0;            // for value metrics
  json record;                   // study.json's "reference"
};
// The reference: an exact value, an earlier run, or a configuration run first (std::runtime_error when that
// run fails: there is nothing to measure against).
ReferenceResult establish_reference(const Study& study, Runner& runner);
// Measures a successful run against the reference (row.error, and row.nrmse or row.value); a metric that cannot
// be computed turns the row's status into "metric_failed". NRMSE runs get compare.json and histograms.svg.
class Measure {
 public:
  Measure(const Study& study, const ReferenceResult& reference, const std::vector<std::filesystem::path>& plugin_paths);
  ~Measure();
  void operator()(Row& row, const std::filesystem::path& folder) const;

 private:
  const Study& study_;
  const ReferenceResult& reference_;
  std::unique_ptr<PluginCatalog> catalog_;  // for the interpolation of NRMSE comparisons
};
// A run is on the Pareto front when no other successful run is at least as fast and at least as accurate, and
// strictly better in one of the two.
void mark_pareto(std::vector<Row>& rows);

// ---- report
// study.csv, error_vs_time.svg and study.json in `out`.
void write_reports(const OutputFolder& out, const Study& study, const ReferenceResult& reference,
                   const std::vector<Row>& rows, int threads, double study_seconds);
// The table on the terminal.
void print_table(std::ostream& out, const Study& study, const std::vector<Row>& rows, const std::filesystem::path& folder,
                 double study_seconds);

}  // namespace mtled::study
