// A fit's forward runs and searches. Every forward run is an `mtled run` of an experiment's scene with the parameters'
// values set by pointer, in this process or (through a launcher) a child process; a run that goes unstable is recorded
// as a bad point and the search goes on.
// Runs go several at once (a Jacobian's columns, the start points' searches), the threads split between them.
// Levenberg-Marquardt works on forward-difference Jacobians with the bounds kept by fixing a parameter at its bound
// while the gradient pushes it out; BOBYQA (NLopt) is bounded and derivative-free. Both search the unit interval of
// each parameter (log10 of the value for a log-scale parameter).
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <mutex>
#include <nlopt.hpp>
#include <random>
#include <semaphore>
#include <span>
#include <thread>

#include "mtled/analysis/child_run.hpp"
#include "mtled/analysis/fit.hpp"
#include "mtled/analysis/scene_sections.hpp"
#include "mtled/errors.hpp"
#include "mtled/io/mesh_writer.hpp"
#include "mtled/log.hpp"
#include "mtled/markups.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/simulation.hpp"
#include "study_support.hpp"

namespace fs = std::filesystem;

namespace mtled::fit {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

Evaluator::Evaluator(const Plan& plan, const fs::path& output, const std::vector<fs::path>& plugin_paths,
                     std::string log_level, InProcessRunner in_process, fs::path executable)
    : plan_(plan),
      output_(output),
      executable_(executable.empty() ? mtled_program("mtled") : std::move(executable)),
      plugin_paths_(plugin_paths),
      log_level_(std::move(log_level)),
      in_process_(plan.settings.launcher.empty() ? std::move(in_process) : InProcessRunner{}),
      catalog_(std::make_unique<PluginCatalog>(plugin_search_path(plugin_paths, {}))) {
  const int threads = plan.settings.threads > 0 ? plan.settings.threads
                                                : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int searches = 1 + static_cast<int>(plan.settings.extra_starts.size());
  const int wanted = plan.settings.concurrent_runs > 0
                         ? plan.settings.concurrent_runs
                         : static_cast<int>(plan.parameters.size() * plan.experiments.size()) * searches;
  // Launched runs go elsewhere (other machines, their own ranks): the fit's own cores do not bound them.
  at_once_ = plan.settings.launcher.empty() ? std::clamp(wanted, 1, threads) : std::max(wanted, 1);
  threads_ = threads;
  slots_ = std::make_unique<std::counting_semaphore<>>(at_once_);
}

Evaluator::~Evaluator() = default;

std::vector<Evaluation> Evaluator::evaluate(const std::vector<std::vector<double>>& points, int start,
                                            const std::string& purpose) {
  std::vector<Evaluation> out(points.size());
  {
    const std::lock_guard lock(mutex_);
    for (std::size_t p = 0; p < points.size(); ++p) {
      out[p].index = static_cast<int>(history_.size());
      out[p].start = start;
      out[p].purpose = purpose;
      out[p].values = points[p];
      out[p].folder = output_ / "runs" / fmt::format("{:04d}", out[p].index);
      history_.push_back(out[p]);  // its place; filled in when it is finished
    }
  }
  // One job per point and experiment, at most at_once_ runs at a time over every caller.
  const std::size_t experiments = plan_.experiments.size();
  std::vector<RunOutcome> outcomes(points.size() * experiments);
  std::vector<std::thread> jobs;
  // A batch smaller than the runs allowed at once gives each run more threads (a trial point gets them all); a
  // launched run has its own machine's threads.
  const int threads = plan_.settings.launcher.empty()
                          ? std::max(1, threads_ / std::min(at_once_, static_cast<int>(outcomes.size())))
                          : threads_;
  for (std::size_t j = 0; j < outcomes.size(); ++j)
    jobs.emplace_back([&, j] {
      const ForwardRun forward = forward_run(out[j / experiments], j % experiments, threads);
      fs::create_directories(forward.folder);
      slots_->acquire();
      outcomes[j] = run(forward);
      slots_->release();
    });
  for (auto& t : jobs) t.join();
  for (std::size_t p = 0; p < points.size(); ++p) {
    measure(out[p], std::span(outcomes).subspan(p * experiments, experiments));
    out[p] = finish(std::move(out[p]));
  }
  return out;
}

// Experiment x at the evaluation's values: the experiment's own overrides, the mesh written once, then the parameters.
ForwardRun Evaluator::forward_run(const Evaluation& e, std::size_t x, int threads) const {
  const Experiment& experiment = plan_.experiments[x];
  ForwardRun run{experiment.scene, {}, e.folder / experiment.name, threads, {}, log_level_, plan_.settings.timeout_s};
  for (const auto& [pointer, value] : experiment.set.items()) run.assignments.push_back(pointer + "=" + value.dump());
  if (!experiment.mesh_file.empty())
    run.assignments.push_back("/mesh=" + json{{"type", "abaqus_file"}, {"path", experiment.mesh_file.string()}}.dump());
  for (std::size_t k = 0; k < plan_.parameters.size(); ++k) {
    const std::string& pointer = plan_.parameters[k].pointers[x];
    if (!pointer.empty()) run.assignments.push_back(fmt::format("{}={:.17g}", pointer, e.values[k]));
  }
  for (const auto& p : plugin_paths_) run.plugin_paths.push_back(fs::absolute(p));
  return run;
}

// In this process when there is a runner for it, else a child `mtled run` (behind the launcher, if any).
RunOutcome Evaluator::run(const ForwardRun& run) const {
  if (in_process_) return in_process_(run);
  std::vector<std::string> args{
      "run",         run.scene.string(), "-o",        run.folder.string(),        "--no-progress",
      "--log-level", run.log_level,      "--threads", std::to_string(run.threads)};
  for (const auto& assignment : run.assignments) args.insert(args.end(), {"--set", assignment});
  for (const auto& p : run.plugin_paths) args.insert(args.end(), {"--plugin-path", p.string()});
  const std::vector<std::string>& launcher = plan_.settings.launcher;
  if (launcher.empty()) return run_child(executable_, args, run.folder / "mtled.log", run.timeout_s);
  args.insert(args.begin(), executable_.string());
  args.insert(args.begin(), launcher.begin() + 1, launcher.end());
  return run_child(fs::path(launcher.front()), args, run.folder / "mtled.log", run.timeout_s);
}

// The evaluation's predictions and weighted residuals from its runs' folders; a run that failed makes it a bad point
// (no objective) with the run's own diagnosis.
void Evaluator::measure(Evaluation& e, std::span<const RunOutcome> outcomes) {
  e.status = "ok";
  e.objective = 0.0;
  for (std::size_t x = 0; x < plan_.experiments.size(); ++x) {
    const RunOutcome& o = outcomes[x];
    const Experiment& experiment = plan_.experiments[x];
    e.wall_s = std::max(e.wall_s, o.elapsed_s);
    const fs::path folder = e.folder / experiment.name;
    const json summary = study::read_json_file(folder / "summary.json");
    const std::string status = o.timed_out           ? "timeout"
                               : summary.is_object() ? summary.value("status", "failed")
                                                     : "failed";
    std::vector<double> model;
    if (status == "ok" && o.exit_code == 0) {
      try {
        const std::lock_guard lock(mutex_);
        model = predictions(experiment, folder, *catalog_);
      } catch (const std::exception& error) {
        e.status = "failed";
        e.message = error.what();
      }
    } else {
      e.status = status == "ok" ? "failed" : status;
      const json d = summary.is_object() ? summary.value("diagnostic", json()) : json();
      e.message =
          fmt::format("experiment {}: {}{}", experiment.name, e.status,
                      d.is_object() ? ": " + d.value("detail", "") : "; see " + (folder / "mtled.log").string());
    }
    std::vector<double> r;
    for (std::size_t i = 0; i < model.size(); ++i) {
      r.push_back((model[i] - experiment.data[i].value) / experiment.data[i].sigma);
      e.objective += r.back() * r.back();
    }
    e.model.push_back(std::move(model));
    e.residuals.push_back(std::move(r));
  }
  if (e.status != "ok") e.objective = NAN;
  log().info("fit: evaluation {} ({}{}): {}", e.index, e.purpose, e.start ? fmt::format(", start {}", e.start) : "",
             e.status == "ok" ? fmt::format("objective {:.6g}", e.objective) : e.message);
}

Evaluation Evaluator::finish(Evaluation e) {
  const std::lock_guard lock(mutex_);
  history_[static_cast<std::size_t>(e.index)] = e;
  return e;
}

double write_meshes_once(Plan& plan, const fs::path& output, const std::vector<fs::path>& plugin_paths) {
  const auto start = Clock::now();
  for (std::size_t x = 0; x < plan.experiments.size(); ++x) {
    Experiment& e = plan.experiments[x];
    const auto changes = [&](const std::string& section) {
      return std::any_of(plan.parameters.begin(), plan.parameters.end(), [&](const Parameter& p) {
        return p.pointers[x] == section || p.pointers[x].rfind(section + "/", 0) == 0;
      });
    };
    if (changes("/mesh")) continue;
    SceneDocument document = read_scene(e.scene);
    for (const auto& [pointer, value] : e.set.items()) apply_override(document, pointer + "=" + value.dump());
    for (const auto& p : plan.parameters)
      if (!p.pointers[x].empty()) apply_override(document, fmt::format("{}={:.17g}", p.pointers[x], p.start));
    PluginCatalog catalog(plugin_search_path(plugin_paths, scene_plugin_paths(document)));
    const Scene scene = validate_scene(std::move(document), catalog, run_scene_sections());
    MeshInputs inputs;
    const TetMesh mesh = load_scene_mesh(scene, catalog, &inputs);
    if (inputs.asked_needle_path && changes("/needle")) {
      // Refined along the needle's path, which a parameter may move: each run's mesh follows its own needle (runs in
      // the fit's process still share a basis while the path stays).
      log().info(
          "fit: experiment {}'s mesh is refined along the needle, a parameter of which is fitted: the runs "
          "mesh along their own needle's path",
          e.name);
      continue;
    }
    e.mesh_file = fs::absolute(output / "meshes" / (e.name + ".inp"));
    fs::create_directories(e.mesh_file.parent_path());
    write_abaqus_mesh(mesh, e.mesh_file);
  }
  return std::chrono::duration<double>(Clock::now() - start).count();
}

namespace {

std::vector<double> values_of(const Plan& plan, const Eigen::VectorXd& z) {
  std::vector<double> v;
  for (std::size_t k = 0; k < plan.parameters.size(); ++k)
    v.push_back(plan.parameters[k].value(z[static_cast<Index>(k)]));
  return v;
}

Eigen::VectorXd residual_vector(const Evaluation& e) {
  std::vector<double> all;
  for (const auto& r : e.residuals) all.insert(all.end(), r.begin(), r.end());
  return Eigen::Map<const Eigen::VectorXd>(all.data(), static_cast<Index>(all.size()));
}

// One search's outcome.
struct Search {
  Eigen::VectorXd z;  // scaled parameters of the best point
  Evaluation best;
  Eigen::MatrixXd jacobian_scaled;  // at best, when computed there
  std::string termination;
  bool converged = false;
  bool failed = false;
};

// Forward differences on the unit interval, all columns at once; a column whose run fails is tried on the other
// side, and is zero (the parameter held) when that fails too.
Eigen::MatrixXd jacobian(const Plan& plan, Evaluator& evaluator, const Eigen::VectorXd& z, const Evaluation& base,
                         int start) {
  const Index n = z.size();
  const double h = plan.settings.fd_step;
  std::vector<std::vector<double>> points;
  std::vector<double> steps;
  for (Index k = 0; k < n; ++k) {
    Eigen::VectorXd zk = z;
    const double step = z[k] + h <= 1.0 ? h : -h;
    zk[k] += step;
    points.push_back(values_of(plan, zk));
    steps.push_back(step);
  }
  std::vector<Evaluation> columns = evaluator.evaluate(points, start, "jacobian");
  const Eigen::VectorXd r0 = residual_vector(base);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(r0.size(), n);
  for (Index k = 0; k < n; ++k) {
    Evaluation* c = &columns[static_cast<std::size_t>(k)];
    std::vector<Evaluation> retry;
    if (c->status != "ok") {
      Eigen::VectorXd zk = z;
      steps[static_cast<std::size_t>(k)] = -steps[static_cast<std::size_t>(k)];
      zk[k] += steps[static_cast<std::size_t>(k)];
      if (zk[k] < 0.0 || zk[k] > 1.0) continue;
      retry = evaluator.evaluate({values_of(plan, zk)}, start, "jacobian");
      c = &retry[0];
      if (c->status != "ok") continue;
    }
    J.col(k) = (residual_vector(*c) - r0) / steps[static_cast<std::size_t>(k)];
  }
  return J;
}

// The parameters a step may move: not one at a bound that the gradient pushes further out, nor one the data do not
// depend on (a zero column: no step in it means anything).
std::vector<Index> free_parameters(const Eigen::MatrixXd& A, const Eigen::VectorXd& g, const Eigen::VectorXd& z) {
  std::vector<Index> free;
  const double sensitive = 1e-14 * A.diagonal().maxCoeff();
  for (Index k = 0; k < z.size(); ++k)
    if (A(k, k) > sensitive && !((z[k] <= 0.0 && g[k] > 0.0) || (z[k] >= 1.0 && g[k] < 0.0))) free.push_back(k);
  return free;
}

// z plus the damped Gauss-Newton step (A + lambda diag A) d = -g in the free parameters, clipped to the unit interval.
Eigen::VectorXd damped_trial(const Eigen::MatrixXd& A, const Eigen::VectorXd& g, const Eigen::VectorXd& z,
                             const std::vector<Index>& free, double lambda) {
  const Index m = static_cast<Index>(free.size());
  Eigen::MatrixXd Af(m, m);
  Eigen::VectorXd gf(m);
  for (Index i = 0; i < m; ++i) {
    gf[i] = g[free[i]];
    for (Index j = 0; j < m; ++j) Af(i, j) = A(free[i], free[j]);
    Af(i, i) += lambda * std::max(A(free[i], free[i]), 1e-12);
  }
  const Eigen::VectorXd d = Af.ldlt().solve(-gf);
  Eigen::VectorXd trial = z;
  for (Index i = 0; i < m; ++i) trial[free[i]] = std::clamp(z[free[i]] + d[i], 0.0, 1.0);
  return trial;
}

// After one outer iteration of levenberg_marquardt: whether the search ends there, with out.converged and
// out.termination saying how.
bool stops_after_iteration(Search& out, bool accepted, bool small_step, bool none_free, double lambda,
                           int max_evaluations) {
  if (out.converged) {
    out.jacobian_scaled.resize(0, 0);  // computed before the last step: not at the optimum
    return true;
  }
  if (small_step || none_free) {
    out.converged = true;
    out.termination = none_free ? "no parameter can move: each is at a bound the data push it past, or the data "
                                  "do not depend on it"
                                : "converged: the next step promises less than the tolerance";
    return true;
  }
  if (!accepted) {
    out.termination = lambda >= 1e10 ? "no step lowers the objective (damping at its limit)"
                                     : fmt::format("the budget of {} evaluations is spent", max_evaluations);
    out.converged = lambda >= 1e10;  // a minimum within the runs' own noise
    return true;
  }
  return false;
}

Search levenberg_marquardt(const Plan& plan, Evaluator& evaluator, Eigen::VectorXd z, int start) {
  const Settings& s = plan.settings;
  Search out;
  auto budget_left = [&] { return static_cast<int>(evaluator.history().size()) < s.max_evaluations; };
  Evaluation current = evaluator.evaluate({values_of(plan, z)}, start, "start")[0];
  if (current.status != "ok") {
    out.failed = true;
    out.best = current;
    out.z = z;
    out.termination = fmt::format("the run at the start point failed: {}", current.message);
    return out;
  }
  double lambda = 1e-3;
  const Index n = z.size();
  const bool sigma_known =
      std::all_of(plan.experiments.begin(), plan.experiments.end(), [](const Experiment& e) { return e.sigma_given; });
  while (true) {
    if (!budget_left()) {
      out.termination = fmt::format("the budget of {} evaluations is spent", s.max_evaluations);
      break;
    }
    const Eigen::MatrixXd J = jacobian(plan, evaluator, z, current, start);
    out.jacobian_scaled = J;
    const Eigen::VectorXd r = residual_vector(current);
    const Eigen::VectorXd g = J.transpose() * r;
    const Eigen::MatrixXd A = J.transpose() * J;
    const std::vector<Index> free = free_parameters(A, g, z);
    bool accepted = false, small_step = false;
    Eigen::VectorXd rejected = Eigen::VectorXd::Constant(n, -1.0);  // a trial already refused: not run again
    while (!accepted && budget_left() && lambda < 1e10 && !free.empty()) {
      const Eigen::VectorXd trial = damped_trial(A, g, z, free, lambda);
      if ((trial - z).lpNorm<Eigen::Infinity>() < s.tolerance) {  // below what the runs' own noise resolves
        small_step = true;
        break;
      }
      if ((trial - rejected).norm() < 1e-12) {  // the bounds clipped a longer step to the same point
        lambda *= 10.0;
        continue;
      }
      // What the linear model promises: below what matters, no run is worth it. With the data's standard deviations
      // known, a change of chi^2 under 0.01 moves no parameter by more than a tenth of its standard error.
      const Eigen::VectorXd step = trial - z;
      const double promised = -(2.0 * g.dot(step) + step.dot(A * step));
      if (promised < std::max(s.tolerance * current.objective, sigma_known ? 0.01 : 0.0)) {
        small_step = true;
        break;
      }
      const Evaluation t = evaluator.evaluate({values_of(plan, trial)}, start, "trial")[0];
      if (t.status == "ok" && t.objective < current.objective) {
        const double reduction = (current.objective - t.objective) / std::max(current.objective, 1e-300);
        const double moved = (trial - z).lpNorm<Eigen::Infinity>();
        z = trial;
        current = t;
        lambda = std::max(lambda / 10.0, 1e-9);
        accepted = true;
        if (reduction < s.tolerance || moved < s.tolerance) {
          out.converged = true;
          out.termination = fmt::format(
              "converged: the last step lowered the objective by {:.2g} (relative) and moved "
              "the parameters by {:.2g} of their ranges",
              reduction, moved);
        }
      } else {
        rejected = trial;
        lambda *= 10.0;
      }
    }
    if (stops_after_iteration(out, accepted, small_step, free.empty(), lambda, s.max_evaluations)) break;
  }
  out.z = z;
  out.best = current;
  return out;
}

Search bobyqa(const Plan& plan, Evaluator& evaluator, Eigen::VectorXd z0, int start) {
  const Settings& s = plan.settings;
  const std::size_t n = plan.parameters.size();
  nlopt::opt opt(nlopt::LN_BOBYQA, static_cast<unsigned>(n));
  opt.set_lower_bounds(std::vector<double>(n, 0.0));
  opt.set_upper_bounds(std::vector<double>(n, 1.0));
  opt.set_maxeval(std::max(1, s.max_evaluations - static_cast<int>(evaluator.history().size())));
  opt.set_ftol_rel(s.tolerance);
  opt.set_xtol_abs(s.tolerance);  // a step below the tolerance of the range: below what the runs resolve
  opt.set_initial_step(0.1);
  Search out;
  double penalty = HUGE_VAL;  // for a failed run: far above anything seen
  struct Context {
    const Plan* plan;
    Evaluator* evaluator;
    Search* out;
    double* penalty;
    int start;
  } context{&plan, &evaluator, &out, &penalty, start};
  opt.set_min_objective(
      [](const std::vector<double>& x, std::vector<double>&, void* data) {
        auto& c = *static_cast<Context*>(data);
        const Eigen::VectorXd z = Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Index>(x.size()));
        const Evaluation e = c.evaluator->evaluate({values_of(*c.plan, z)}, c.start, "trial")[0];
        if (e.status != "ok") return std::isfinite(*c.penalty) ? *c.penalty : 1e300;
        *c.penalty =
            std::isfinite(*c.penalty) ? std::max(*c.penalty, 1e3 * e.objective) : 1e3 * std::max(e.objective, 1.0);
        if (c.out->best.status != "ok" || e.objective < c.out->best.objective) {
          c.out->best = e;
          c.out->z = z;
        }
        return e.objective;
      },
      &context);
  std::vector<double> x(z0.data(), z0.data() + z0.size());
  double minimum = 0.0;
  try {
    const nlopt::result r = opt.optimize(x, minimum);
    out.converged = r == nlopt::FTOL_REACHED || r == nlopt::XTOL_REACHED || r == nlopt::SUCCESS;
    out.termination = r == nlopt::MAXEVAL_REACHED
                          ? fmt::format("the budget of {} evaluations is spent", s.max_evaluations)
                          : fmt::format("BOBYQA: {}", out.converged ? "converged" : "stopped");
  } catch (const std::exception& error) {
    out.termination = fmt::format("BOBYQA stopped: {}", error.what());
  }
  if (out.best.status != "ok") {
    out.failed = true;
    out.termination = "no run of the search succeeded";
  }
  return out;
}

}  // namespace

Result solve(const Plan& plan, Evaluator& evaluator) {
  const auto clock_start = Clock::now();
  std::vector<Eigen::VectorXd> starts;
  Eigen::VectorXd z(static_cast<Index>(plan.parameters.size()));
  for (std::size_t k = 0; k < plan.parameters.size(); ++k)
    z[static_cast<Index>(k)] = plan.parameters[k].scaled(plan.parameters[k].start);
  starts.push_back(z);
  for (const auto& values : plan.settings.extra_starts) {
    for (std::size_t k = 0; k < values.size(); ++k)
      z[static_cast<Index>(k)] = std::clamp(plan.parameters[k].scaled(values[k]), 0.0, 1.0);
    starts.push_back(z);
  }
  // Every start point's search at once; they share the evaluator's runs.
  std::vector<Search> searches(starts.size());
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < starts.size(); ++i)
    threads.emplace_back([&, i] {
      searches[i] = plan.settings.method == Method::bobyqa
                        ? bobyqa(plan, evaluator, starts[i], static_cast<int>(i))
                        : levenberg_marquardt(plan, evaluator, starts[i], static_cast<int>(i));
    });
  for (auto& t : threads) t.join();

  Result result;
  const Search* best = nullptr;
  for (const auto& s : searches)
    if (!s.failed && (!best || s.best.objective < best->best.objective)) best = &s;
  if (!best) {
    result.termination = searches[0].termination;
  } else {
    result.values = best->best.values;
    result.best = best->best.index;
    result.termination = best->termination;
    result.converged = best->converged;
    // The Jacobian at the optimum, for the standard errors: computed there unless the search's last one was.
    Eigen::MatrixXd J = best->jacobian_scaled;
    if (J.size() == 0) J = jacobian(plan, evaluator, best->z, best->best, static_cast<int>(best - searches.data()));
    // d(residual)/d(value) = d(residual)/d(scaled) * d(scaled)/d(value)
    for (std::size_t k = 0; k < plan.parameters.size(); ++k)
      J.col(static_cast<Index>(k)) /= plan.parameters[k].slope(result.values[k]);
    result.jacobian = J;
  }
  result.evaluations = evaluator.history();
  result.seconds = std::chrono::duration<double>(Clock::now() - clock_start).count();
  return result;
}

namespace {

// Standard normal numbers from a seed, the same on every platform (Box-Muller on the 64-bit Mersenne twister).
class Noise {
 public:
  explicit Noise(unsigned long long seed) : engine_(seed) {}
  double operator()() {
    const double u1 = (static_cast<double>(engine_() >> 11) + 0.5) * 0x1.0p-53;
    const double u2 = (static_cast<double>(engine_() >> 11) + 0.5) * 0x1.0p-53;
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::mt19937_64 engine_;
};

// An "after" 3D Slicer markups file: each marker moved by the model's displacement plus noise, in millimetres, in
// the frame of the "before" file.
json synthetic_markups(const Experiment& ex, const std::vector<double>& model, Noise& noise) {
  const MarkupsPoints before = read_markups(ex.markups_before);
  const bool flipped = ex.markups_frame != before.frame;
  json points = json::array();
  for (std::size_t i = 0; i < ex.data.size(); i += 3) {
    Vec3 moved;
    for (int c = 0; c < 3; ++c) moved[c] = ex.data[i].position[c] + model[i + c] + ex.data[i + c].sigma * noise();
    if (flipped) moved = flip_lps_ras(moved);
    points.push_back({{"label", ex.data[i].label},
                      {"position", {1e3 * moved[0], 1e3 * moved[1], 1e3 * moved[2]}},
                      {"positionStatus", "defined"}});
  }
  return {{"markups",
           {{{"type", "Fiducial"},
             {"coordinateSystem", before.frame},
             {"coordinateUnits", "mm"},
             {"controlPoints", points}}}}};
}

}  // namespace

void synthesize(const Plan& plan, Evaluator& evaluator, unsigned long long seed, const fs::path& folder) {
  for (const auto& e : plan.experiments)
    if (!e.sigma_given)
      throw InputError(plan.document.locate(e.where + "/sigma"),
                       "synthetic data need the data's standard deviation: give \"sigma\" (or a sigma column)");
  std::vector<double> truth;
  for (const auto& p : plan.parameters) truth.push_back(p.start);
  const Evaluation e = evaluator.evaluate({truth}, 0, "synthesize")[0];
  if (e.status != "ok") throw std::runtime_error(fmt::format("the run at the start values failed: {}", e.message));
  Noise noise(seed);
  fs::create_directories(folder);
  for (std::size_t x = 0; x < plan.experiments.size(); ++x) {
    const Experiment& ex = plan.experiments[x];
    std::ofstream out(folder / ex.data_file.filename());
    const auto& model = e.model[x];
    if (!ex.markups_before.empty()) {
      out << synthetic_markups(ex, model, noise).dump(2) << "\n";
      continue;
    }
    if (ex.quantity == Quantity::markers) {
      out << "label,x_m,y_m,z_m,ux_m,uy_m,uz_m,sigma_m\n";
      for (std::size_t i = 0; i < ex.data.size(); i += 3) {
        const Datum& d = ex.data[i];
        out << fmt::format("{},{:.9g},{:.9g},{:.9g}", d.label, d.position[0], d.position[1], d.position[2]);
        for (int c = 0; c < 3; ++c) out << fmt::format(",{:.9g}", model[i + c] + ex.data[i + c].sigma * noise());
        out << fmt::format(",{:.9g}\n", d.sigma);
      }
      continue;
    }
    out << (ex.quantity == Quantity::needle_force ? "depth_m" : "displacement_m") << ",force_N,sigma_N\n";
    for (std::size_t i = 0; i < ex.data.size(); ++i) {
      const double sigma = std::isfinite(ex.data[i].sigma) ? ex.data[i].sigma : ex.sigma_relative * std::abs(model[i]);
      out << fmt::format("{:.9g},{:.9g},{:.9g}\n", ex.data[i].abscissa, model[i] + sigma * noise(), sigma);
    }
  }
  log().info("wrote synthetic data at the start values (seed {}) in {}", seed, folder.string());
}

}  // namespace mtled::fit
