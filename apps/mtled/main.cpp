// mtled: the command line (its commands: README.md); exit codes: 0 ok, 1 other failure, 2 invalid input,
// 3 numerical instability.
#include <CLI/CLI.hpp>

#include <iostream>

#include "commands.hpp"
#include "mtled/errors.hpp"
#include "mtled/json.hpp"
#include "mtled/log.hpp"
#include "mtled/simd.hpp"
#include "mtled/version.hpp"
#include "processes.hpp"

namespace {

struct Commands {
  std::string log_level = "info";
  std::vector<std::filesystem::path> plugin_paths;
  std::string simd = "best";
  std::string backend;  // run --backend: the scene's /backend block
  mtled::app::RunOptions run;
  mtled::app::SceneOptions validate;
  mtled::app::MeshOptions mesh;
  bool as_json = false, as_markdown = false;
  std::string describe;
  mtled::app::CompareOptions compare;
  mtled::app::FieldOptions field;
  mtled::app::WarpOptions warp;
  mtled::app::StudyOptions study;
  mtled::app::FitOptions fit;
  mtled::app::ConformanceOptions conformance;
  CLI::App *run_cmd = nullptr, *validate_cmd = nullptr, *plugins_cmd = nullptr, *schema_cmd = nullptr,
           *compare_cmd = nullptr, *study_cmd = nullptr, *conformance_cmd = nullptr, *mesh_cmd = nullptr,
           *fit_cmd = nullptr, *field_cmd = nullptr, *warp_cmd = nullptr;
};

void add_global_options(CLI::App& cli, Commands& c) {
  cli.add_option("--log-level", c.log_level, "trace, debug, info, warn, error or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));
  cli.add_option("--plugin-path", c.plugin_paths, "extra plugin folder, searched first (repeatable)");
  cli.add_option("--simd", c.simd,
                 "instruction set of the vectorised kernels: best (the default: the best this CPU has), or one of "
                 "avx512, avx2, sse4, baseline (the portable one) to compare; answers agree to round-off");
}

void add_scene_commands(CLI::App& cli, Commands& c) {
  c.run_cmd = cli.add_subcommand("run", "run a scene");
  c.run_cmd->add_option("scene", c.run.scene.scene, "scene file (JSON)")->required();
  c.run_cmd->add_option("-o,--output", c.run.output, "output folder (default: out/<scene name>)");
  c.run_cmd->add_option("--set", c.run.scene.overrides, "override a scene value: /json/pointer=value (repeatable)");
  c.run_cmd->add_option("--threads", c.run.threads, "threads for the force loop (default: OMP_NUM_THREADS when set, else all cores)")
      ->check(CLI::NonNegativeNumber);
  c.run_cmd->add_flag("!--no-progress", c.run.progress, "no progress display (it only shows on a terminal anyway)");
  c.run_cmd->add_option("--backend", c.backend,
                        "where the time step runs: cpu, or a backend plugin such as cuda (sets the scene's "
                        "/backend; mtled plugins lists those built)");

  c.mesh_cmd = cli.add_subcommand("mesh", "write a scene's mesh (read or generated) as an Abaqus .inp file");
  c.mesh_cmd->add_option("scene", c.mesh.scene.scene, "scene file (JSON)")->required();
  c.mesh_cmd->add_option("-o,--output", c.mesh.output, "the .inp file to write")->required();
  c.mesh_cmd->add_option("--set", c.mesh.scene.overrides, "override a scene value: /json/pointer=value (repeatable)");

  c.validate_cmd = cli.add_subcommand("validate", "check a scene against every named component's parameters");
  c.validate_cmd->add_option("scene", c.validate.scene, "scene file (JSON)")->required();
  c.validate_cmd->add_option("--set", c.validate.overrides, "override a scene value: /json/pointer=value");

  c.plugins_cmd = cli.add_subcommand("plugins", "list the components mtled can load");
  c.plugins_cmd->add_flag("--json", c.as_json, "machine-readable list");
  c.plugins_cmd->add_flag("--markdown", c.as_markdown, "the parameter reference (docs/parameters.md)");
  c.plugins_cmd->add_option("--describe", c.describe, "one component's parameters (NAME or CATEGORY/NAME)");

  c.schema_cmd = cli.add_subcommand("schema", "print the JSON Schema of scenes (for editors)");

  c.conformance_cmd = cli.add_subcommand(
      "conformance", "run mtled's conformance suites on a plugin library (materials, shape functions, integrators)");
  c.conformance_cmd->add_option("library", c.conformance.library, "mtled-CATEGORY-NAME.so, or a folder of them")
      ->required();
  c.conformance_cmd->add_option("--gtest", c.conformance.gtest_arguments,
                                "an argument for the GoogleTest runner, such as --gtest=--gtest_brief=1 (repeatable)");
}

// Back to the image: the field on an image grid and the warped image (docs/label-maps.md).
void add_image_commands(CLI::App& cli, Commands& c) {
  c.field_cmd = cli.add_subcommand(
      "field", "a run's displacement on an image's grid, as a displacement-field image (NRRD, NIfTI) for 3D Slicer "
               "and ITK (docs/label-maps.md)");
  c.field_cmd->add_option("run", c.field.run, "run folder (or result .vtu)")->required();
  auto* like =
      c.field_cmd->add_option("--like", c.field.like, "image whose grid the field is sampled on (NRRD, NIfTI)");
  auto* origin =
      c.field_cmd->add_option("--origin", c.field.origin_mm, "or the grid: its first voxel's centre (mm)")->expected(3);
  auto* spacing = c.field_cmd->add_option("--spacing", c.field.spacing_mm, "the grid's spacing (mm): 1 or 3 numbers")
                      ->expected(1, 3)
                      ->check(CLI::PositiveNumber);
  auto* size = c.field_cmd->add_option("--size", c.field.size, "the grid's voxels along each axis")
                   ->expected(3)
                   ->check(CLI::PositiveNumber);
  auto* space = c.field_cmd->add_option("--space", c.field.space, "the grid's frame: LPS or RAS")
                    ->check(CLI::IsMember({"LPS", "RAS"}));
  for (CLI::Option* grid : {origin, spacing, size, space}) {
    grid->excludes(like);
    for (CLI::Option* other : {origin, spacing, size, space})
      if (other != grid) grid->needs(other);
  }
  c.field_cmd->add_option("-o,--output", c.field.output, "the field (.nrrd, or .nii / .nii.gz: RAS, intent DISPVECT)")
      ->required();
  c.field_cmd->add_option("--direction", c.field.direction,
                          "resampling (default: at each voxel of the deformed body, the step back to its reference "
                          "point, what Slicer and ITK resample with) or forward (at each voxel of the reference body, "
                          "where its material goes)");
  c.field_cmd->add_option("--frame", c.field.frame, "LPS or RAS: the frame of a mesh that records none");
  c.field_cmd->add_option("--decay", c.field.decay_mm,
                          "outside the body, the nearest surface value fading to zero over this many mm (default 10; "
                          "0: zero outside)")
      ->check(CLI::NonNegativeNumber);

  c.warp_cmd = cli.add_subcommand(
      "warp", "an image (the pre-operative MRI, the label map) resampled into a run's deformed state (docs/label-maps.md)");
  c.warp_cmd->add_option("image", c.warp.image, "scalar image in the scene's frame (NRRD, NIfTI)")->required();
  c.warp_cmd->add_option("run", c.warp.run, "run folder (or result .vtu)")->required();
  c.warp_cmd->add_option("-o,--output", c.warp.output, "the warped image (.nrrd, .nii or .nii.gz)")->required();
  c.warp_cmd->add_option("--interpolation", c.warp.interpolation,
                         "linear (intensities) or nearest (labels); default: nearest for whole-number voxel types, "
                         "else linear");
  c.warp_cmd->add_option("--frame", c.warp.frame, "LPS or RAS: the frame of a mesh that records none");
  c.warp_cmd->add_option("--decay", c.warp.decay_mm,
                         "outside the body, the displacement fades to zero over this many mm (default 10; 0: the "
                         "image outside the deformed body is not moved)")
      ->check(CLI::NonNegativeNumber);
}

void add_analysis_commands(CLI::App& cli, Commands& c) {
  c.compare_cmd = cli.add_subcommand(
      "compare", "NRMSE per displacement component between two runs (A interpolated onto B's nodes when they differ)");
  c.compare_cmd->add_option("run_a", c.compare.a, "run folder (or result .vtu) A")->required();
  c.compare_cmd->add_option("run_b", c.compare.b, "run folder (or result .vtu) B: the reference, whose nodes are used")
      ->required();
  c.compare_cmd->add_flag("--json", c.compare.json, "machine-readable output");
  c.compare_cmd->add_option("--histogram", c.compare.histogram, "write histograms of u_A - u_B per component (SVG)");
  c.compare_cmd->add_option("--bins", c.compare.bins, "histogram bins (default 41)")->check(CLI::PositiveNumber);

  c.study_cmd = cli.add_subcommand("study", "run a sweep of scene settings against a reference (docs/studies.md)");
  c.study_cmd->add_option("study", c.study.study, "study file (JSON)")->required();
  c.study_cmd->add_option("-o,--output", c.study.output, "the study's folder (study.csv, study.json, error_vs_time.svg, runs/)")
      ->required();
  c.study_cmd->add_option("--threads", c.study.threads, "threads for every run (default: the study's \"threads\", else all)")
      ->check(CLI::NonNegativeNumber);
  c.study_cmd->add_flag("--reuse", c.study.reuse,
                        "keep runs whose folder already holds a successful result of the same scene and settings");
  c.study_cmd->add_option("--job-list", c.study.job_list,
                          "write one command line per run to this file instead of running them (for a batch "
                          "scheduler); then --gather");
  c.study_cmd->add_flag("--gather", c.study.gather,
                        "run nothing: measure the runs a job list made in the study's folder and write the report");

  c.fit_cmd = cli.add_subcommand("fit", "identify scene parameters from measurements (docs/calibration.md)");
  c.fit_cmd->add_option("fit", c.fit.fit, "fit file (JSON)")->required();
  c.fit_cmd->add_option("-o,--output", c.fit.output, "the fit's folder (fit.json, fit.csv, fit_data.csv, fit.svg, runs/)")
      ->required();
  c.fit_cmd->add_option("--set", c.fit.overrides, "override a value of the fit file: /json/pointer=value (repeatable)");
  c.fit_cmd->add_option("--threads", c.fit.threads, "threads in all, split between the runs that go at once")
      ->check(CLI::NonNegativeNumber);
  c.fit_cmd->add_flag("!--no-mesh-reuse", c.fit.reuse_mesh,
                      "generate each run's mesh and build its meshless basis again instead of once");
  c.fit_cmd->add_flag("--check", c.fit.check, "check the fit file, its data files and every scene; run nothing");
  c.fit_cmd->add_option("--synthesize", c.fit.synthesize,
                        "write each data file again under OUTPUT/data from the model at the start values plus "
                        "Gaussian noise of the data's sigma, seeded with this number; fit nothing");
}

int dispatch(Commands& c) {
  using namespace mtled;
  simd::use(c.simd);
  if (*c.run_cmd) {
    if (!c.backend.empty()) c.run.scene.overrides.push_back("/backend=" + json{{"type", c.backend}}.dump());
    return app::run_scene(c.run);
  }
  if (*c.validate_cmd) return app::validate_scene_command(c.validate);
  if (*c.mesh_cmd) return app::mesh_command(c.mesh);
  if (*c.plugins_cmd) return app::list_plugins(c.plugin_paths, c.as_json, c.as_markdown, c.describe);
  if (*c.schema_cmd) return app::print_schema(c.plugin_paths);
  if (*c.compare_cmd) return app::compare_command(c.compare, c.plugin_paths);
  if (*c.field_cmd) return app::field_command(c.field, c.plugin_paths);
  if (*c.warp_cmd) return app::warp_command(c.warp, c.plugin_paths);
  if (*c.study_cmd) return app::study_command(c.study);
  if (*c.fit_cmd) return app::fit_command(c.fit);
  if (*c.conformance_cmd) return app::conformance_command(c.conformance, c.plugin_paths);
  return 1;
}

}  // namespace

// Under mpirun, the commands other than run and study compute nothing that ranks could share.
bool runs_on_these_ranks(const Commands& c) {
  if (mtled::app::processes().size() == 1 || *c.run_cmd || *c.study_cmd) return true;
  mtled::log().error("this command runs on one process: run it without mpirun (`mtled run` and `mtled study` use "
                     "several ranks)");
  return false;
}

// A rank's error: rank 0's as it is, the others' prefixed with their rank (a failure only one rank met names it).
void report(const std::string& message) {
  const mtled::ProcessGroup& group = mtled::app::processes();
  if (group.rank() == 0)
    mtled::log().error("{}", message);
  else
    mtled::log().error("rank {} of {}: {}", group.rank(), group.size(), message);
}

int main(int argc, char** argv) {
  using namespace mtled;
  CLI::App cli{"mtled: meshless total Lagrangian explicit dynamics for needle insertion into soft tissue"};
  cli.set_version_flag("--version", MTLED_VERSION_STRING);
  cli.require_subcommand(1);
  cli.fallthrough();  // global options may follow the subcommand: mtled run scene.json --log-level debug
  Commands c;
  add_global_options(cli, c);
  add_scene_commands(cli, c);
  add_analysis_commands(cli, c);
  add_image_commands(cli, c);
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = cli.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    app::join_processes(c.plugin_paths);
  } catch (const InputError& e) {
    for (const auto& problem : e.problems()) log().error("{}", problem.format());
    return 2;
  } catch (const std::exception& e) {  // the group's plugin failed to start (MPI's initialisation)
    log().error("joining the launcher's processes failed: {}", e.what());
    return 1;
  }
  // The other ranks say only what went wrong; rank 0 tells the run.
  set_log_level(app::processes().writes() ? c.log_level : "error");
  if (!runs_on_these_ranks(c)) return 2;
  c.run.scene.plugin_paths = c.validate.plugin_paths = c.mesh.scene.plugin_paths = c.study.plugin_paths = c.fit.plugin_paths =
      c.plugin_paths;
  c.study.log_level = c.log_level;
  int code = 1;
  try {
    code = dispatch(c);
  } catch (const InputError& e) {
    for (const auto& problem : e.problems()) report(problem.format());
    return 2;
  } catch (const InstabilityError& e) {
    report(e.what());
    code = 3;
  } catch (const std::exception& e) {
    report(e.what());
    return 1;
  }
  if (code == 0 || code == 3) app::processes().finish();  // every rank ends alike only then (process_group.hpp)
  return code;
}
