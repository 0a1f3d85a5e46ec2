// mtled run: build the scene, run it, write the outputs (summary.json last).
#include <fmt/format.h>
#include <omp.h>
#include <sys/resource.h>

#include <atomic>
#include <cstdlib>
#include <chrono>
#include <csignal>
#include <thread>

#include "commands.hpp"
#include "mtled/analysis/postprocess.hpp"
#include "mtled/log.hpp"
#include "mtled/monitors/scene_monitors.hpp"
#include "mtled/io/output.hpp"
#include "mtled/simd.hpp"
#include "mtled/simulation.hpp"
#include "mtled/version.hpp"
#include "progress.hpp"

namespace fs = std::filesystem;

namespace mtled::app {

namespace {

std::atomic<bool> interrupted{false};
extern "C" void on_interrupt(int) { interrupted = true; }

struct Interrupted : std::runtime_error {
  Interrupted() : std::runtime_error("interrupted (Ctrl-C)") {}
};

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

json vec_json(const Vec3& v) { return json::array({v[0], v[1], v[2]}); }

VtuFormat vtu_format(const Parameters& output) {
  return output.string("vtu_format") == "ascii" ? VtuFormat::ascii : VtuFormat::binary;
}

// Records needle.csv and reactions.csv rows, steps/*.vtu snapshots and the progress display. Under an integrator
// that relaxes (dynamic relaxation), needle.csv and reactions.csv hold each relaxed state (forces in equilibrium)
// and needle_transient.csv and reactions_transient.csv the rows along the way; otherwise the first two hold the
// rows.
class RunObserver final : public StepObserver {
 public:
  RunObserver(const OutputFolder& folder, const Simulation& simulation, const Parameters& output, bool progress)
      : folder_(folder),
        history_every_(output.integer("history_every_steps")),
        snapshot_every_(output.integer("every_steps")),
        format_(vtu_format(output)),
        relaxing_(simulation.integrator().report().relaxation.has_value()),
        progress_(progress) {
    if (simulation.needle() != nullptr) {
      needle_ = folder.open_stream("needle.csv");
      needle_.out() << "time_s,depth_m,force_N,phase\n";
      if (relaxing_) {
        needle_transient_ = folder.open_stream("needle_transient.csv");
        needle_transient_.out() << "time_s,depth_m,transient_force_N,phase\n";
      }
    }
    if (!simulation.constraint_sets().empty()) {
      reactions_ = folder.open_stream("reactions.csv");
      reactions_.out() << "time_s,set,fx_N,fy_N,fz_N\n";
      if (relaxing_) {
        reactions_transient_ = folder.open_stream("reactions_transient.csv");
        reactions_transient_.out() << "time_s,set,transient_fx_N,transient_fy_N,transient_fz_N\n";
      }
    }
    if (snapshot_every_ > 0) snapshot(simulation);  // the series starts with the initial state
  }

  void on_step(const Simulation& simulation) override {
    if (interrupted) throw Interrupted();
    const long step = simulation.step();
    if (step % history_every_ == 0) record(simulation);
    if (relaxing_) record_equilibrium(simulation);
    if (snapshot_every_ > 0 && step % snapshot_every_ == 0 && step > 0) snapshot(simulation);
    if (progress_.due()) progress_.draw(simulation.load_fraction(), progress_text(simulation));
  }

  void finish(const Simulation& simulation) {
    progress_.finish();
    if (last_recorded_ != simulation.step()) record(simulation);
    needle_.commit();
    needle_transient_.commit();
    reactions_.commit();
    reactions_transient_.commit();
    // ... and ends with the final one, which the run's last step need not be a multiple of every_steps to reach.
    if (snapshot_every_ > 0 && last_snapshot_ != simulation.step()) snapshot(simulation);
    if (!snapshots_.empty()) {
      folder_.write_file("series.pvd", [&](std::ostream& out) {
        out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
        for (const auto& [time, file] : snapshots_)
          out << fmt::format("<DataSet timestep=\"{:.10g}\" file=\"{}\"/>\n", time, file);
        out << "</Collection>\n</VTKFile>\n";
      });
    }
  }

 private:
  static std::string progress_text(const Simulation& simulation) {
    std::string text = fmt::format("step {}  t {:.4g} s", simulation.step(), simulation.time());
    if (const auto* needle = simulation.needle())
      text += fmt::format("  depth {:.2f} mm  force {:.4g} N  {}", 1e3 * needle->status().depth,
                          needle->status().force, to_string(needle->status().phase));
    // Once the load is on, a relaxation is most of a run: show how far it still has to go.
    if (simulation.load_fraction() >= 1.0) {
      if (const auto relaxation = simulation.integrator().report().relaxation)
        text += fmt::format("  relaxing: error {:.2g} (tolerance {:.2g})", relaxation->relative_error_bound,
                            relaxation->tolerance);
    }
    return text;
  }

  static void needle_row(const Simulation& simulation, OutputFolder::Stream& stream) {
    const NeedleStatus s = simulation.needle()->status();
    stream.out() << fmt::format("{:.10g},{:.10g},{:.10g},{}\n", simulation.time(), s.depth, s.force, to_string(s.phase));
  }

  static void reaction_rows(const Simulation& simulation, OutputFolder::Stream& stream) {
    for (const auto* set : simulation.constraint_sets()) {
      const Vec3 r = set->total_reaction();
      stream.out() << fmt::format("{:.10g},{},{:.10g},{:.10g},{:.10g}\n", simulation.time(), set->name, r[0], r[1], r[2]);
    }
  }

  // needle.csv and reactions.csv rows at each state the relaxation reports steady.
  void record_equilibrium(const Simulation& simulation) {
    if (simulation.steady_states() == steady_states_) return;
    steady_states_ = simulation.steady_states();
    if (needle_.is_open()) needle_row(simulation, needle_);
    if (reactions_.is_open()) reaction_rows(simulation, reactions_);
  }

  void record(const Simulation& simulation) {
    last_recorded_ = simulation.step();
    if (needle_.is_open()) needle_row(simulation, relaxing_ ? needle_transient_ : needle_);
    if (reactions_.is_open()) reaction_rows(simulation, relaxing_ ? reactions_transient_ : reactions_);
  }

  void snapshot(const Simulation& simulation) {
    const std::string file = fmt::format("steps/{:06d}.vtu", simulation.step());
    const auto u = simulation.interpolated_displacement();
    folder_.write_file(file, [&](std::ostream& out) { write_vtu(out, simulation.model().mesh(), u, {}, format_); });
    snapshots_.emplace_back(simulation.time(), file);
    last_snapshot_ = simulation.step();
  }

  const OutputFolder& folder_;
  long history_every_, snapshot_every_;
  VtuFormat format_;
  bool relaxing_;
  long last_recorded_ = -1, last_snapshot_ = -1;
  long steady_states_ = 0;
  OutputFolder::Stream needle_, needle_transient_, reactions_, reactions_transient_;
  std::vector<std::pair<double, std::string>> snapshots_;
  Progress progress_;
};

}  // namespace

namespace {

// --threads, else OMP_NUM_THREADS when set (the OpenMP convention), else every core.
int thread_count(const RunOptions& options) {
  if (options.threads > 0) return options.threads;
  if (std::getenv("OMP_NUM_THREADS")) return omp_get_max_threads();
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// One `mtled run`: the output folder, summary.json as it grows, the simulation and its observer. summary.json is
// written first with status "running" and last with the outcome, so it always says how the run ended.
class SceneRun {
 public:
  SceneRun(const RunOptions& options, const Scene& scene, PluginCatalog& catalog, Clock::time_point wall_start)
      : wall_start_(wall_start),
        scene_(scene),
        catalog_(catalog),
        folder_(options.output.empty() ? fs::path("out") / options.scene.scene.stem() : options.output) {
    folder_.clear_previous_outputs();
    const int threads = thread_count(options);
    omp_set_num_threads(threads);
    summary_ = {{"status", "running"},
                {"mtled_version", MTLED_VERSION_STRING},
                {"scene", fs::absolute(options.scene.scene).string()},
                {"overrides", options.scene.overrides},
                {"threads", threads},
                {"simd", simd::current()}};
    write_summary();
  }

  int run(bool progress) {
    try {
      const auto setup_start = Clock::now();
      simulation_ = std::make_unique<Simulation>(scene_, catalog_);
      add_scene_monitors(*simulation_, scene_);
      setup_time_ = seconds_since(setup_start);
      summary_["backend"] = simulation_->backend();
      log().info("setup {:.2f} s; critical time step {:.4g} s", setup_time_, simulation_->unscaled_stable_time_step());
      observer_ = std::make_unique<RunObserver>(folder_, *simulation_, scene_.output, progress);
      solve_start_ = Clock::now();
      simulation_->run(observer_.get());
      observer_->finish(*simulation_);
    } catch (const InstabilityError& e) {
      return unstable(e);
    } catch (const Interrupted&) {
      return finish_without_result("interrupted", seconds_since(solve_start_), "");
    } catch (const InputError& e) {
      const InputError located = locate_problems(e, scene_.document);
      finish_without_result("invalid_input", 0.0, located.what());
      throw located;
    } catch (const std::exception& e) {
      finish_without_result("failed", 0.0, e.what());
      throw;
    }
    return succeeded(seconds_since(solve_start_));
  }

 private:
  void write_summary() const {
    folder_.write_file("summary.json", [&](std::ostream& out) { out << summary_.dump(2) << "\n"; });
  }

  // What every outcome records: timings, memory, the plugins loaded, and the model, steps and monitors.
  void record(double solve_time) {
    summary_["plugins_loaded"] = catalog_.loaded_files();
    summary_["setup_time_s"] = setup_time_;
    summary_["solve_time_s"] = solve_time;
    summary_["wall_time_s"] = seconds_since(wall_start_);
    summary_["peak_rss_mb"] = peak_rss_mb();
    if (!simulation_) return;
    const Model& model = simulation_->model();
    const auto stats = model.ip_support_statistics();
    summary_["nodes"] = model.node_count();
    summary_["integration_points"] = model.integration_point_count();
    summary_["support_size"] = {{"min", stats.min}, {"mean", stats.mean}, {"max", stats.max}};
    summary_["min_reciprocal_condition"] = stats.min_reciprocal_condition;
    summary_["backend"] = simulation_->backend();  // with what it counted over the run
    summary_["steps"] = simulation_->step();
    summary_["simulated_time_s"] = simulation_->time();
    summary_["stable_time_step_s"] = simulation_->unscaled_stable_time_step();
    summary_["constraint_factorisations"] = simulation_->constraints().factorisations();
    summary_["force_evaluations"] = simulation_->force_evaluations();
    summary_["monitors"] = simulation_->monitor_reports();
    summary_["ip_updates_per_s"] = solve_time > 0 ? static_cast<double>(simulation_->force_evaluations()) *
                                                        model.integration_point_count() / solve_time
                                                  : 0.0;
    const IntegratorReport report = simulation_->integrator().report();
    summary_["integrator"] = to_json(report);
    if (report.relaxation) summary_["integrator"]["relaxed_states"] = simulation_->steady_states();
    summary_["time_step_s"] = report.time_step;
  }

  // status "unstable" with the diagnostic and the last state whose forces were admissible (never named
  // result.vtu); exit 3.
  int unstable(const InstabilityError& e) {
    if (observer_) observer_->finish(*simulation_);
    record(seconds_since(solve_start_));
    const Diagnostic& d = e.diagnostic();
    json where = json::array();
    for (std::size_t i = 0; i < d.coordinates.size(); ++i) {
      json item = {{"coordinates_m", vec_json(d.coordinates[i])}};
      if (i < d.nodes.size()) item["node"] = d.nodes[i];
      if (i < d.integration_points.size()) item["integration_point"] = d.integration_points[i];
      where.push_back(item);
    }
    summary_["status"] = "unstable";
    summary_["diagnostic"] = {{"step", d.step}, {"time_s", d.time}, {"what", d.what}, {"detail", d.detail}, {"where", where}};
    const auto last = d.what == "inverted_material" ? simulation_->previous_displacement() : simulation_->displacement();
    std::vector<double> u(last.size());
    simulation_->model().interpolate(last, u);
    folder_.write_file("last_good_state.vtu", [&](std::ostream& out) {
      write_vtu(out, simulation_->model().mesh(), u, {}, vtu_format(scene_.output));
    });
    summary_["last_good_state"] = "last_good_state.vtu";
    write_summary();
    log().error("{}", e.what());
    log().error("wrote {} with status \"unstable\"", (folder_.path() / "summary.json").string());
    return 3;
  }

  int finish_without_result(const std::string& status, double solve_time, const std::string& error) {
    record(solve_time);
    summary_["status"] = status;
    if (!error.empty()) summary_["error"] = error;
    write_summary();
    if (status == "interrupted")
      log().error("interrupted at step {}; {} says so", simulation_ ? simulation_->step() : 0,
                  (folder_.path() / "summary.json").string());
    return 1;
  }

  // result.vtu, then summary.json with status "ok": the needle, the reactions and the error indicators.
  int succeeded(double solve_time) {
    const auto u = simulation_->interpolated_displacement();
    double max_displacement = 0.0;
    for (std::size_t i = 0; i < u.size(); i += 3)
      max_displacement = std::max(max_displacement, std::sqrt(u[i] * u[i] + u[i + 1] * u[i + 1] + u[i + 2] * u[i + 2]));
    const auto fields = cell_fields(simulation_->model(), simulation_->displacement(), scene_.output.string_list("cell_data"));
    folder_.write_file("result.vtu", [&](std::ostream& out) {
      write_vtu(out, simulation_->model().mesh(), u, fields, vtu_format(scene_.output));
    });
    record(solve_time);
    summary_["max_displacement_m"] = max_displacement;
    if (const auto* needle = simulation_->needle()) {
      const NeedleStatus s = needle->status();
      summary_["needle"] = {{"final_depth_m", s.depth},
                            {"final_force_N", s.force},
                            {"puncture_depth_m", s.puncture_depth >= 0 ? json(s.puncture_depth) : json(nullptr)},
                            {"phase", to_string(s.phase)},
                            {"driven_nodes", s.driven_nodes}};
    }
    json reactions = json::object();
    for (const auto* set : simulation_->constraint_sets()) reactions[set->name] = vec_json(set->total_reaction());
    summary_["final_reactions_N"] = reactions;
    summary_["error_indicators"] = error_indicators(*simulation_);
    summary_["status"] = "ok";
    write_summary();
    log().info("done: {} steps, solve {:.2f} s, {:.3g} integration-point updates/s; results in {}", simulation_->step(),
               solve_time, summary_["ip_updates_per_s"].get<double>(), folder_.path().string());
    return 0;
  }

  const Clock::time_point wall_start_;  // before the scene was read
  const Scene& scene_;
  PluginCatalog& catalog_;
  const OutputFolder folder_;
  json summary_;
  Clock::time_point solve_start_ = Clock::now();
  double setup_time_ = 0.0;
  std::unique_ptr<Simulation> simulation_;
  std::unique_ptr<RunObserver> observer_;
};

}  // namespace

int run_scene(const RunOptions& options) {
  const auto wall_start = Clock::now();
  SceneDocument document = read_scene(options.scene.scene, options.scene.overrides);
  PluginCatalog catalog(plugin_search_path(options.scene.plugin_paths, scene_plugin_paths(document)));
  const Scene scene = validate_scene(std::move(document), catalog);
  SceneRun run(options, scene, catalog, wall_start);
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  return run.run(options.progress);
}

}  // namespace mtled::app
