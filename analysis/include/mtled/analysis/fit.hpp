#pragma once
// A fit (`mtled fit`, docs/calibration.md): scene parameters identified from measurements. The parameters are JSON
// pointers into one or more experiments' scenes, each experiment a scene with a measured data file; every forward
// run is an `mtled run` of its own, in the fit's process (its mesh and meshless basis built once) or, through a
// launcher, a child process (an unstable one is recorded either way and the fit goes on). Four parts, one file each:
//   plan      (fit_plan.cpp)      read the fit file and every data file, check them all before anything runs;
//   data      (fit_data.cpp)      what a run predicts at each datum (needle force at a depth, a set's reaction at a
//                                 displacement, a marker's displacement), read back from the run's folder;
//   solve     (fit_solve.cpp)     the forward runs (several at once), Levenberg-Marquardt and BOBYQA;
//   report    (fit_report.cpp)    standard errors, correlations, identifiability; fit.json, fit.csv, fit.svg.
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <semaphore>
#include <span>
#include <string>
#include <vector>

#include "mtled/analysis/child_run.hpp"
#include "mtled/json.hpp"
#include "mtled/scene.hpp"
#include "mtled/types.hpp"

namespace mtled::fit {

struct Parameter {
  std::string name;
  std::vector<std::string> pointers;  // one per experiment (empty: the parameter does not enter that experiment)
  double lower = 0.0, upper = 0.0, start = 0.0;
  bool log_scale = false;  // searched in log10(value): for a parameter that spans decades (a strain threshold, D)
  // The unit interval the methods search in, and back.
  double scaled(double value) const;
  double value(double scaled) const;
  double slope(double value) const;  // d value / d scaled at the value
};

enum class Quantity { needle_force, reaction_force, markers };

// One measured datum: where it was measured (a depth, a displacement, a marker's reference position), the
// measured value, its standard deviation, and where in which file it came from (for messages).
struct Datum {
  double abscissa = 0.0;         // needle_force: depth (m); reaction_force: the set's displacement (m)
  Vec3 position = Vec3::Zero();  // markers: reference position (m)
  int component = 0;             // markers: 0, 1, 2 for ux, uy, uz (each marker gives three data)
  std::string label;             // markers: the marker's label
  double value = 0.0;
  double sigma = 1.0;
  std::string source;  // "data.csv:12", or "after.mrk.json: /markups/0/controlPoints/3"
};

struct Experiment {
  std::string name;
  std::string where;                       // its place in the fit file, for messages
  std::filesystem::path scene, data_file;  // markers from 3D Slicer: data_file the "after" markups file
  std::filesystem::path markups_before;    // ... and this the "before" one (empty for a CSV file)
  std::string markups_frame;               // their frame ("LPS", "RAS"), put into the mesh's when it records one
  json set = json::object();               // its own scene overrides, applied before the parameters
  Quantity quantity = Quantity::needle_force;
  std::string set_name;         // reaction_force: the constrained set
  int component = 2;            // reaction_force: the force and displacement component
  bool sigma_given = false;     // a standard deviation (not a relative weight) was given
  double sigma_relative = 0.0;  // > 0: each datum's standard deviation is this fraction of its magnitude
  std::vector<Datum> data;
  // Filled by the checks: what the forward runs need.
  double displacement_full = 0.0;   // reaction_force: the set's prescribed displacement component at full load
  int relaxed_increments = 1;       // reaction_force, needle_force: equilibrium rows the run writes
  double depth_full = 0.0;          // needle_force: the needle's final depth
  std::filesystem::path mesh_file;  // a mesh written once and read by every run (empty: the scene's own)
};

enum class Method { levenberg_marquardt, bobyqa };

struct Settings {
  Method method = Method::levenberg_marquardt;
  int max_evaluations = 60;
  double tolerance = 1e-4;  // relative change of the objective, or of the scaled parameters, that ends the search
  double fd_step = 0.01;    // forward-difference step on the unit interval
  std::vector<std::vector<double>> extra_starts;  // further start points (restarts)
  int threads = 0;  // in all, split between the runs that go at once (0: every core); with a launcher, each run's
  int concurrent_runs = 0;  // forward runs at once (0: one per parameter and start; at most the threads, unless launched)
  double timeout_s = 0.0;   // a forward run still going after this long is stopped and counted as failed
  // A command put before each forward run (srun ..., mpirun -np 4): runs on other machines of a batch job, or each
  // on several ranks. Its program is found on PATH when the fit file is read.
  std::vector<std::string> launcher;
};

struct Plan {
  std::filesystem::path file;
  SceneDocument document;  // the fit file, for locating its pointers
  std::string description;
  std::vector<Parameter> parameters;
  std::vector<Experiment> experiments;
  Settings settings;
};

// ---- plan
// Reads the fit file (with --set overrides on it), every data file and every experiment's scene; InputError with
// every problem (file and line, or fit file and JSON pointer) before anything runs.
Plan read(const std::filesystem::path& file, const std::vector<std::string>& overrides,
          const std::vector<std::filesystem::path>& plugin_paths);

// Every datum has its standard deviation (a relative one needs a measured value other than 0); a template for
// --synthesize need not.
void check_measured(const Plan& plan);

// ---- data
// What the run in `folder` predicts at each of the experiment's data, in the data's order (InputError naming the
// folder when its files lack what is needed).
std::vector<double> predictions(const Experiment& experiment, const std::filesystem::path& folder,
                                PluginCatalog& catalog);

// ---- solve
struct Evaluation {
  int index = 0;
  int start = 0;               // which start point's search made it
  std::string purpose;         // "start", "jacobian", "trial", "optimum"
  std::vector<double> values;  // parameter values
  std::string status;          // "ok", or how a forward run failed ("unstable", "failed", "timeout", ...)
  std::string message;
  double objective = NAN;                      // sum of squared weighted residuals; NaN when a run failed
  std::vector<std::vector<double>> residuals;  // per experiment, (model - datum) / sigma
  std::vector<std::vector<double>> model;      // per experiment, the predictions
  double wall_s = 0.0;
  std::filesystem::path folder;
};

struct Result {
  std::vector<double> values;  // the best parameters found
  int best = -1;               // its evaluation
  std::vector<Evaluation> evaluations;
  std::string termination;  // why the search ended, in words
  bool converged = false;
  Eigen::MatrixXd jacobian;  // d(weighted residuals) / d(parameter values) at the best point (empty when failed)
  double seconds = 0.0;
  double setup_seconds = 0.0;  // meshes written once
};

// One forward run, as `mtled run SCENE -o FOLDER --set ...` does it.
struct ForwardRun {
  std::filesystem::path scene;
  std::vector<std::string> assignments;  // "/pointer=value", as --set: the experiment's own, its mesh, the parameters
  std::filesystem::path folder;
  int threads = 1;
  std::vector<std::filesystem::path> plugin_paths;
  std::string log_level;  // of the run's log, FOLDER/mtled.log
  double timeout_s = 0.0;
};
// Runs one in the calling process and says how it ended (exit_code as `mtled run`'s): the command line's own run,
// which this library does not link, handed in by whoever makes the Evaluator.
using InProcessRunner = std::function<RunOutcome(const ForwardRun&)>;

// The forward runs: each an experiment's scene with the parameters' values set, run by `in_process` or, with a
// launcher (or no runner), as a child `mtled run`.
class Evaluator {
 public:
  // `executable`: the mtled a child run starts (empty: mtled's own, mtled_program).
  Evaluator(const Plan& plan, const std::filesystem::path& output,
            const std::vector<std::filesystem::path>& plugin_paths, std::string log_level,
            InProcessRunner in_process = {}, std::filesystem::path executable = {});
  ~Evaluator();
  // Evaluates several parameter sets at once (each experiment of each set a run, concurrent_runs at a time).
  std::vector<Evaluation> evaluate(const std::vector<std::vector<double>>& points, int start,
                                   const std::string& purpose);
  const std::vector<Evaluation>& history() const { return history_; }
  int runs_at_once() const { return at_once_; }
  int threads() const { return threads_; }

 private:
  ForwardRun forward_run(const Evaluation& e, std::size_t experiment, int threads) const;
  RunOutcome run(const ForwardRun& run) const;
  void measure(Evaluation& e, std::span<const RunOutcome> outcomes);
  Evaluation finish(Evaluation e);
  const Plan& plan_;
  std::filesystem::path output_, executable_;
  std::vector<std::filesystem::path> plugin_paths_;
  std::string log_level_;
  InProcessRunner in_process_;  // empty with a launcher: child runs
  std::unique_ptr<PluginCatalog> catalog_;
  std::vector<Evaluation> history_;
  int at_once_ = 1, threads_ = 1;                     // runs at once at most, and the threads they share
  std::unique_ptr<std::counting_semaphore<>> slots_;  // at_once_ of them: a run takes one while it goes
  std::mutex mutex_;  // history_ and the catalog the predictions use, between the searches' threads
};

// Writes each experiment's mesh once (when it is generated and no parameter changes it) so that every forward run
// reads it instead of generating it again; returns the seconds spent.
double write_meshes_once(Plan& plan, const std::filesystem::path& output,
                         const std::vector<std::filesystem::path>& plugin_paths);

// Runs the plan's method from every start point; the best result.
Result solve(const Plan& plan, Evaluator& evaluator);

// Evaluates the experiments at the start values and writes each data file again with the model's values plus
// Gaussian noise of the data's standard deviations (seeded): data with a known truth, to check a design.
void synthesize(const Plan& plan, Evaluator& evaluator, unsigned long long seed, const std::filesystem::path& folder);

// ---- report
struct Statistics {
  bool sigma_estimated = false;    // no standard deviations given: the residuals' variance estimates them
  double residual_variance = 1.0;  // s^2 used in the covariance
  double chi_square = NAN;         // sum of squared weighted residuals at the optimum
  Eigen::MatrixXd covariance;      // of the parameter values
  Eigen::VectorXd standard_error;
  Eigen::MatrixXd correlation;
  std::vector<double> r_squared;              // per experiment
  std::vector<std::string> not_identifiable;  // one sentence per parameter the data cannot pin down
  std::vector<std::string> warnings;          // at a bound, failed runs, ...
};
Statistics statistics(const Plan& plan, const Result& result);
// fit.json, fit.csv and fit.svg in `folder`; the summary on the terminal.
void write_report(const Plan& plan, const Result& result, const Statistics& stats, const std::filesystem::path& folder);
void print_summary(std::ostream& out, const Plan& plan, const Result& result, const Statistics& stats);

}  // namespace mtled::fit
