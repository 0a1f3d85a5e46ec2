// mtled: the command line. See docs/cli.md; exit codes: 0 ok, 1 other failure, 2 invalid input,
// 3 numerical instability.
#include <CLI/CLI.hpp>

#include <iostream>

#include "commands.hpp"
#include "mtled/errors.hpp"
#include "mtled/log.hpp"
#include "mtled/simd.hpp"
#include "mtled/version.hpp"

int main(int argc, char** argv) {
  using namespace mtled;
  CLI::App cli{"mtled: meshless total Lagrangian explicit dynamics for needle insertion into soft tissue"};
  cli.set_version_flag("--version", MTLED_VERSION_STRING);
  cli.require_subcommand(1);
  cli.fallthrough();  // global options may follow the subcommand: mtled run scene.json --log-level debug
  std::string log_level = "info";
  cli.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));
  std::vector<std::filesystem::path> plugin_paths;
  cli.add_option("--plugin-path", plugin_paths, "extra plugin folder, searched first (repeatable)");
  std::string simd = "best";
  cli.add_option("--simd", simd,
                 "instruction set of the vectorised kernels: best (the default: the best this CPU has), or one of "
                 "avx512, avx2, sse4, baseline (the portable one) to compare; answers agree to round-off");

  app::RunOptions run;
  auto* run_cmd = cli.add_subcommand("run", "run a scene");
  run_cmd->add_option("scene", run.scene.scene, "scene file (JSON)")->required();
  run_cmd->add_option("-o,--output", run.output, "output folder (default: out/<scene name>)");
  run_cmd->add_option("--set", run.scene.overrides, "override a scene value: /json/pointer=value (repeatable)");
  run_cmd->add_option("--threads", run.threads, "threads for the force loop (default: OMP_NUM_THREADS when set, else all cores)")
      ->check(CLI::NonNegativeNumber);
  run_cmd->add_flag("!--no-progress", run.progress, "no progress display (it only shows on a terminal anyway)");

  app::SceneOptions validate;
  auto* validate_cmd = cli.add_subcommand("validate", "check a scene against every named component's parameters");
  validate_cmd->add_option("scene", validate.scene, "scene file (JSON)")->required();
  validate_cmd->add_option("--set", validate.overrides, "override a scene value: /json/pointer=value");

  bool as_json = false, as_markdown = false;
  std::string describe;
  auto* plugins_cmd = cli.add_subcommand("plugins", "list the components mtled can load");
  plugins_cmd->add_flag("--json", as_json, "machine-readable list");
  plugins_cmd->add_flag("--markdown", as_markdown, "the parameter reference (docs/parameters.md)");
  plugins_cmd->add_option("--describe", describe, "one component's parameters (NAME or CATEGORY/NAME)");

  auto* schema_cmd = cli.add_subcommand("schema", "print the JSON Schema of scenes (for editors)");

  app::CompareOptions compare;
  auto* compare_cmd = cli.add_subcommand(
      "compare", "NRMSE per displacement component between two runs (A interpolated onto B's nodes when they differ)");
  compare_cmd->add_option("run_a", compare.a, "run folder (or result .vtu) A")->required();
  compare_cmd->add_option("run_b", compare.b, "run folder (or result .vtu) B: the reference, whose nodes are used")
      ->required();
  compare_cmd->add_flag("--json", compare.json, "machine-readable output");
  compare_cmd->add_option("--histogram", compare.histogram, "write histograms of u_A - u_B per component (SVG)");
  compare_cmd->add_option("--bins", compare.bins, "histogram bins (default 41)")->check(CLI::PositiveNumber);

  app::StudyOptions study;
  auto* study_cmd = cli.add_subcommand("study", "run a sweep of scene settings against a reference (docs/studies.md)");
  study_cmd->add_option("study", study.study, "study file (JSON)")->required();
  study_cmd->add_option("-o,--output", study.output, "the study's folder (study.csv, study.json, error_vs_time.svg, runs/)")
      ->required();
  study_cmd->add_option("--threads", study.threads, "threads for every run (default: the study's \"threads\", else all)")
      ->check(CLI::NonNegativeNumber);
  study_cmd->add_flag("--reuse", study.reuse,
                      "keep runs whose folder already holds a successful result of the same scene and settings");

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = cli.exit(e);
    return code == 0 ? 0 : 2;
  }
  set_log_level(log_level);
  run.scene.plugin_paths = validate.plugin_paths = study.plugin_paths = plugin_paths;
  study.log_level = log_level;

  try {
    simd::use(simd);
    if (*run_cmd) return app::run_scene(run);
    if (*validate_cmd) return app::validate_scene_command(validate);
    if (*plugins_cmd) return app::list_plugins(plugin_paths, as_json, as_markdown, describe);
    if (*schema_cmd) return app::print_schema(plugin_paths);
    if (*compare_cmd) return app::compare_command(compare, plugin_paths);
    if (*study_cmd) return app::study_command(study);
  } catch (const InputError& e) {
    for (const auto& problem : e.problems()) log().error("{}", problem.format());
    return 2;
  } catch (const InstabilityError& e) {
    log().error("{}", e.what());
    return 3;
  } catch (const std::exception& e) {
    log().error("{}", e.what());
    return 1;
  }
  return 1;
}
