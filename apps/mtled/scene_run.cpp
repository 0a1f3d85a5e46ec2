// One run on the process that writes: its folder, its summary and its outcome (scene_run.hpp).
#include "scene_run.hpp"

#include "mtled/analysis/postprocess.hpp"
#include "mtled/io/image.hpp"
#include "mtled/log.hpp"
#include "mtled/simd.hpp"
#include "mtled/version.hpp"

namespace fs = std::filesystem;

namespace mtled::app {

namespace {

double seconds_since(SceneRun::Clock::time_point start) {
  return std::chrono::duration<double>(SceneRun::Clock::now() - start).count();
}

// The folder, cleared of an earlier run's files before anything is written.
OutputFolder cleared_output_folder(const RunOptions& options) {
  OutputFolder folder(options.output.empty() ? fs::path("out") / options.scene.scene.stem() : options.output);
  folder.clear_previous_outputs();
  return folder;
}

}  // namespace

SceneRun::SceneRun(const RunOptions& options, const Scene& scene, PluginCatalog& catalog, int threads,
                   Clock::time_point wall_start, BasisCache* bases)
    : wall_start_(wall_start),
      scene_(scene),
      catalog_(catalog),
      bases_(bases),
      plugin_paths_(options.scene.plugin_paths),
      folder_(cleared_output_folder(options)),
      summary_(folder_, {{"mtled_version", MTLED_VERSION_STRING},
                         {"scene", fs::absolute(options.scene.scene).string()},
                         {"overrides", options.scene.overrides},
                         {"threads", threads},
                         {"simd", simd::current()}}) {}

int SceneRun::run(const std::vector<std::shared_ptr<StepMonitor>>& observers) {
  try {
    const auto setup_start = Clock::now();
    simulation_ = std::make_unique<Simulation>(scene_, catalog_, bases_);
    check_displacement_field();
    folded_ = add_scene_monitors(*simulation_, scene_);
    writers_ = add_scene_writers(*simulation_, scene_, folder_);
    for (const auto& observer : observers) {
      simulation_->loop().add_monitor(observer);
      if (auto writer = std::dynamic_pointer_cast<OutputWriter>(observer)) writers_.push_back(writer);
    }
    setup_time_ = seconds_since(setup_start);
    summary_["backend"] = simulation_->system().backend();
    log().info("setup {:.2f} s; critical time step {:.4g} s", setup_time_,
               simulation_->system().unscaled_stable_time_step());
    solve_start_ = Clock::now();
    simulation_->loop().run();
  } catch (const InstabilityError& e) {
    return unstable(e);
  } catch (const RunStopped& e) {
    return finish_without_result(e.status, seconds_since(solve_start_), "");
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

// What every outcome records: timings, memory, the plugins loaded, and the model, steps and monitors.
void SceneRun::record(double solve_time) {
  summary_.record_resources(catalog_, setup_time_, solve_time, seconds_since(wall_start_));
  if (simulation_) summary_.record_simulation(*simulation_, solve_time);
}

// status "unstable" with the diagnostic and the last state whose forces were admissible (never named result.vtu);
// the writers keep their history up to it. Exit 3.
int SceneRun::unstable(const InstabilityError& e) {
  const StepRecord last = simulation_->system().last_step();
  for (const auto& writer : writers_) writer->finish(last);
  record(seconds_since(solve_start_));
  const bool inverted = e.diagnostic().what == "inverted_material";
  std::vector<CellField> folds;
  if (folded_ && !folded_->per_tet.empty()) folds.push_back({"folded", 1, folded_->per_tet});
  written_state_ = inverted ? simulation_->system().previous_displacement() : simulation_->system().displacement();
  written_displacement_ = write_state(folder_, "last_good_state.vtu", simulation_->system().force_kernel(),
                                      written_state_, scene_.section("output"), false, folds);
  // An inverted point beside the needle: where, against the needle, and what the scene can still do about it.
  Diagnostic diagnostic = e.diagnostic();
  const auto needle =
      simulation_->system().needle() ? std::optional(simulation_->system().needle()->status()) : std::nullopt;
  if (inverted && needle && !diagnostic.coordinates.empty())
    diagnostic.detail += fold_advice_at(scene_, *needle, diagnostic.coordinates.front());
  summary_.record_instability(diagnostic, "last_good_state.vtu");
  summary_.write();
  log().error("{}", InstabilityError(diagnostic).what());
  log().error("wrote {} with status \"unstable\"", (folder_.path() / "summary.json").string());
  return 3;
}

int SceneRun::finish_without_result(const std::string& status, double solve_time, const std::string& error) {
  record(solve_time);
  summary_["status"] = status;
  if (!error.empty()) summary_["error"] = error;
  summary_.write();
  // Asked for (a callback's "stop") is no error; Ctrl-C ends a run the user expected to finish.
  if (status == "interrupted" || status == "stopped")
    log().log(status == "stopped" ? spdlog::level::info : spdlog::level::err, "{} at step {}; {} says so", status,
              simulation_ ? simulation_->system().step() : 0, (folder_.path() / "summary.json").string());
  return 1;
}

// The output section's displacement field needs an image with a frame and a mesh that records its own: checked
// before the run, not after it.
void SceneRun::check_displacement_field() const {
  const auto like = scene_.section("output").read<OutputSettings>().displacement_field_like;
  if (!like) return;
  if (simulation_->system().discretisation().mesh().coordinate_system.empty())
    throw InputError("/output/displacement_field_like",
                     "the mesh records no patient frame (LPS or RAS), so where it lies in the image is not known: "
                     "mesh the image itself (a label_map mesh source records it), or leave this out and run mtled "
                     "field with --frame after the run");
  if (read_image(*like).space.empty())
    throw InputError(like->string(), "space: the image names no patient frame (LPS or RAS)");
}

// The field on the output section's image, written next to result.vtu (mtled field's work).
void SceneRun::write_displacement_field() const {
  const auto output = scene_.section("output").read<OutputSettings>();
  if (!output.displacement_field_like) return;
  FieldOptions field;
  field.run = folder_.path();
  field.like = *output.displacement_field_like;
  field.output = folder_.path() / (output.displacement_field_format == "nifti" ? "displacement_field.nii.gz"
                                                                               : "displacement_field.nrrd");
  field.direction = output.displacement_field_direction;
  field.frame = simulation_->system().discretisation().mesh().coordinate_system;
  field.decay_mm = 1e3 * output.displacement_field_decay;
  field_command(field, plugin_paths_);
}

// result.vtu (and the displacement field the output section asks for), then summary.json with status "ok": the
// needle, the reactions and the error indicators.
int SceneRun::succeeded(double solve_time) {
  written_state_ = simulation_->system().displacement();
  written_displacement_ = write_state(folder_, "result.vtu", simulation_->system().force_kernel(), written_state_,
                                      scene_.section("output"), true);
  try {
    write_displacement_field();
  } catch (const InputError& e) {
    finish_without_result("invalid_input", solve_time, e.what());
    throw;
  }
  record(solve_time);
  summary_.record_result(*simulation_, written_displacement_);
  summary_["error_indicators"] = error_indicators(*simulation_);
  summary_["status"] = "ok";
  summary_.write();
  log().info("done: {} steps, solve {:.2f} s, {:.3g} integration-point updates/s; results in {}",
             simulation_->system().step(), solve_time, summary_["ip_updates_per_s"].get<double>(),
             folder_.path().string());
  return 0;
}

}  // namespace mtled::app
