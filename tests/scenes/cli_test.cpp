// The command line's contract (README.md): exit codes, messages that name the JSON pointer or the
// file, the plugin search path, and summary.json's plugins_loaded.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <sstream>

#include "mtled/mesh.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace mtled {
namespace {

const fs::path kSmallCube = test::source_dir() / "tests/scenes/data/small_cube.json";

// A scene file derived from the small cube with one change, written to the test's scratch folder.
fs::path variant(const std::string& name, const std::function<void(json&)>& change) {
  json scene = test::read_json(kSmallCube);
  change(scene);
  const fs::path file = test::scratch_dir("cli-" + name) / "scene.json";
  test::write_text(file, scene.dump(2));
  return file;
}

// Runs the scene `file` into the folder "out" beside it and expects a detected instability: exit 3, summary.json's
// status "unstable", no result.vtu. Returns summary.json.
json run_expecting_unstable_stop(const fs::path& file) {
  const fs::path out = file.parent_path() / "out";
  const auto result = test::run_mtled({"run", file.string(), "-o", out.string()});
  EXPECT_EQ(result.exit_code, 3) << result.output;
  const json summary = test::read_json(out / "summary.json");
  EXPECT_EQ(summary["status"], "unstable");
  EXPECT_FALSE(fs::exists(out / "result.vtu"));
  return summary;
}

void expect_contains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "expected \"" << part << "\" in:\n" << text;
}

TEST(Cli, RunsTheSmallCubeAndWritesTheContractOutputs) {
  const fs::path out = test::scratch_dir("cli-run");
  const auto result = test::run_mtled({"run", kSmallCube.string(), "-o", out.string(), "--threads", "2"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json summary = test::read_json(out / "summary.json");
  EXPECT_EQ(summary["status"], "ok");
  for (const char* key : {"mtled_version", "scene", "nodes", "integration_points", "steps", "time_step_s", "setup_time_s",
                          "solve_time_s", "wall_time_s", "ip_updates_per_s", "peak_rss_mb", "plugins_loaded",
                          "max_displacement_m"})
    EXPECT_TRUE(summary.contains(key)) << key;
  EXPECT_EQ(summary["plugins_loaded"],
            json::array({"mtled-mesh-box.so", "mtled-shape_function-mls.so", "mtled-material-neo_hookean.so",
                         "mtled-boundary-fixed.so", "mtled-boundary-prescribed_displacement.so",
                         "mtled-integrator-dynamic_relaxation.so"}));
  // The run's own error indicators. At the relaxed steady state the reactions balance: the net force is
  // bounded by the residual the tolerance allows (relative 1e-5 on displacements, so well below 1e-3 of the
  // largest nodal reaction); the body is at rest; the step is the scene's factor of the stable one.
  const json& indicators = summary["error_indicators"];
  EXPECT_LT(indicators["net_force_over_largest_reaction"].get<double>(), 1e-3) << indicators.dump();
  EXPECT_LT(indicators["kinetic_over_strain_energy"].get<double>(), 1e-6) << indicators.dump();
  EXPECT_GT(indicators["strain_energy_J"].get<double>(), 0.0);
  EXPECT_NEAR(indicators["time_step_over_stable"].get<double>(), summary["integrator"]["time_step_factor"].get<double>(),
              1e-9);
  EXPECT_LT(indicators["steady_state_relative_error_bound"].get<double>(),
            summary["integrator"]["tolerance"].get<double>());
  EXPECT_TRUE(fs::exists(out / "result.vtu"));
  EXPECT_TRUE(fs::exists(out / "reactions.csv"));
  EXPECT_FALSE(fs::exists(out / "needle.csv"));  // no needle, no needle output
  expect_contains(test::read_text(out / "reactions.csv"), "time_s,set,fx_N,fy_N,fz_N");
  for (const auto& entry : fs::directory_iterator(out))
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
}

// A whole run on 1 and on 2 threads, on a cloud large enough (4,770 nodes) that the constraint projection's
// row loops and the force kernel's shares all run on the team: a share that missed or repeated points or rows
// would move the answer far more than the summation order of the per-thread force buffers, which is all that
// separates 1 thread from 2 (a few ulps per evaluation; measured NRMSE 1.8e-15 after 1,348 steps). A node whose
// update went missing would keep the relaxation from settling: the step limit, more than twice the steps taken,
// turns that into exit 3 instead of a hang (checked by leaving one node per share out of the update).
TEST(Cli, ARunOnALargeCloudIsTheSameOnOneAndTwoThreads) {
  const fs::path folder = test::scratch_dir("cli-threads");
  std::vector<fs::path> outs;
  for (const std::string threads : {"1", "2"}) {
    outs.push_back(folder / ("threads" + threads));
    const auto result = test::run_mtled({"run", kSmallCube.string(), "-o", outs.back().string(), "--threads", threads,
                                         "--set", "/mesh/target_nodes=5000", "--set", "/integrator/max_steps=3000",
                                         "--no-progress"});
    ASSERT_EQ(result.exit_code, 0) << result.output;
  }
  const json one = test::read_json(outs[0] / "summary.json"), two = test::read_json(outs[1] / "summary.json");
  ASSERT_EQ(two["threads"], 2);
  ASSERT_GE(two["nodes"].get<int>(), 4000);
  EXPECT_EQ(one["steps"], two["steps"]);
  const auto compared = test::run_mtled({"compare", outs[0].string(), outs[1].string(), "--json"});
  ASSERT_EQ(compared.exit_code, 0) << compared.output;
  for (const auto& [component, nrmse] : json::parse(compared.output)["nrmse"].items())
    EXPECT_LE(nrmse.get<double>(), 1e-10) << component;
}

// The backend is chosen in the scene or with --backend. "cpu" is the kernel's own engine, named: the same run, to
// the last bit, as a scene without a backend. A backend that cannot run here stops the run at once (exit 2) and
// says how to run on the CPU: "cuda" is either not built (no CUDA toolkit) or finds no device on CI machines.
TEST(Cli, TheBackendIsChosenByNameAndAMissingOneSaysHowToRunOnTheCpu) {
  const fs::path folder = test::scratch_dir("cli-backend");
  const auto plain = test::run_mtled({"run", kSmallCube.string(), "-o", (folder / "plain").string(), "--no-progress"});
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const auto cpu =
      test::run_mtled({"run", kSmallCube.string(), "-o", (folder / "cpu").string(), "--backend", "cpu", "--no-progress"});
  ASSERT_EQ(cpu.exit_code, 0) << cpu.output;
  EXPECT_EQ(test::read_text(folder / "plain" / "result.vtu"), test::read_text(folder / "cpu" / "result.vtu"));
  EXPECT_EQ(test::read_json(folder / "cpu" / "summary.json")["backend"]["type"], "cpu");
  EXPECT_EQ(test::read_json(folder / "plain" / "summary.json")["backend"]["type"], "cpu");
  const json plugins = test::read_json(folder / "cpu" / "summary.json")["plugins_loaded"];
  EXPECT_NE(std::find(plugins.begin(), plugins.end(), "mtled-backend-cpu.so"), plugins.end()) << plugins.dump();

  const auto cuda = test::run_mtled(
      {"run", kSmallCube.string(), "-o", (folder / "cuda").string(), "--backend", "cuda", "--no-progress"});
  if (cuda.exit_code == 0) {  // built, and a GPU is here
    EXPECT_EQ(test::read_json(folder / "cuda" / "summary.json")["backend"]["type"], "cuda");
    return;
  }
  EXPECT_EQ(cuda.exit_code, 2) << cuda.output;
  expect_contains(cuda.output, "/backend");
  expect_contains(cuda.output, "--backend cpu");
  EXPECT_FALSE(fs::exists(folder / "cuda" / "result.vtu"));
}

// A process that a launcher started among several joins their group through the process_group plugin. Where none is
// on the plugin path it stops before the scene is read (exit 2, nothing written): each process would otherwise run the
// whole scene into the same folder. Without a launcher's variables mtled never looks for one (the same empty plugin
// path then fails on the scene's own plugins).
TEST(Cli, SeveralLaunchedProcessesWithoutAProcessGroupPluginStopAtOnce) {
  const fs::path folder = test::scratch_dir("cli-no-process-group");
  const fs::path no_plugins = folder / "no-plugins";
  fs::create_directories(no_plugins);
  const std::vector<std::string> run = {"run", kSmallCube.string(), "-o", (folder / "run").string(), "--no-progress"};
  const auto launched = test::run_mtled(run, {"OMPI_COMM_WORLD_SIZE=2", "MTLED_PLUGIN_PATH=" + no_plugins.string()});
  EXPECT_EQ(launched.exit_code, 2) << launched.output;
  expect_contains(launched.output, "mpirun");
  expect_contains(launched.output, "no process_group plugin");
  EXPECT_FALSE(fs::exists(folder / "run"));
  const auto alone = test::run_mtled(run, {"MTLED_PLUGIN_PATH=" + no_plugins.string()});
  EXPECT_EQ(alone.exit_code, 2) << alone.output;
  EXPECT_EQ(alone.output.find("process_group"), std::string::npos) << alone.output;
  expect_contains(alone.output, "/materials/0/type");
}

TEST(Cli, ValidatePlugins_AndSchemaWork) {
  auto result = test::run_mtled({"validate", kSmallCube.string()});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  expect_contains(result.output, "valid");
  result = test::run_mtled({"plugins", "--json"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json list = json::parse(result.output);
  std::set<std::string> libraries;
  for (const auto& component : list) {
    for (const char* key : {"name", "category", "library", "parameters"}) EXPECT_TRUE(component.contains(key)) << key;
    libraries.insert(component["library"].get<std::string>());
    for (const auto& p : component["parameters"]) EXPECT_FALSE(p["doc"].get<std::string>().empty()) << component["name"];
  }
  EXPECT_EQ(libraries.size(), list.size()) << "each component is its own shared library";
  result = test::run_mtled({"plugins", "--describe", "ogden"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  expect_contains(result.output, "`alpha`");
  // The example block, pasted into a scene, is the component with its declaration's example parameters.
  const auto at = result.output.find("example, in a scene:");
  ASSERT_NE(at, std::string::npos) << result.output;
  const auto start = result.output.find('"', at + 20), end = result.output.find('\n', start);
  const json block = json::parse("{" + result.output.substr(start, end - start) + "}");
  ASSERT_TRUE(block.contains("materials")) << block.dump();
  EXPECT_EQ(block["materials"][0]["type"], "ogden");
  EXPECT_EQ(block["materials"][0]["mu"], 722.0);
  result = test::run_mtled({"schema"});
  EXPECT_EQ(result.exit_code, 0);
  const json schema = json::parse(result.output);
  EXPECT_TRUE(schema.contains("properties"));
}

TEST(Cli, NegativeMuExitsTwoNamingTheKeyAndRange) {
  const auto file = variant("negative-mu", [](json& s) { s["materials"][0]["mu"] = -1000; });
  const auto result = test::run_mtled({"run", file.string(), "-o", (file.parent_path() / "out").string()});
  EXPECT_EQ(result.exit_code, 2);
  expect_contains(result.output, "/materials/0/mu: -1000 is out of range: allowed > 0 Pa");
  EXPECT_FALSE(fs::exists(file.parent_path() / "out")) << "nothing written for an invalid scene";
}

TEST(Cli, MisspeltKeyAndTypeExitTwoWithSuggestions) {
  auto file = variant("misspelt-key", [](json& s) {
    s["materials"][0]["muu"] = s["materials"][0]["mu"];
    s["materials"][0].erase("mu");
  });
  auto result = test::run_mtled({"validate", file.string()});
  EXPECT_EQ(result.exit_code, 2);
  expect_contains(result.output, "/materials/0/muu: unknown key \"muu\"");
  expect_contains(result.output, "did you mean \"mu\"?");
  expect_contains(result.output, "/materials/0/mu: required");

  file = variant("misspelt-type", [](json& s) { s["materials"][0]["type"] = "neo_hooke"; });
  result = test::run_mtled({"validate", file.string()});
  EXPECT_EQ(result.exit_code, 2);
  expect_contains(result.output, "/materials/0/type: unknown material \"neo_hooke\"; did you mean \"neo_hookean\"?");
}

TEST(Cli, TruncatedJsonExitsTwoNamingTheFileAndLine) {
  const fs::path file = test::scratch_dir("cli-truncated") / "cut.json";
  const std::string text = test::read_text(kSmallCube);
  test::write_text(file, text.substr(0, text.size() / 2));
  const auto result = test::run_mtled({"run", file.string()});
  EXPECT_EQ(result.exit_code, 2);
  expect_contains(result.output, "cut.json:");
  expect_contains(result.output, "truncated");
}

TEST(Cli, PluginPathWithoutNeedlePlugins) {
  // A folder holding every plugin except the needle models.
  const fs::path folder = test::scratch_dir("cli-no-needle") / "plugins";
  fs::create_directories(folder);
  for (const auto& entry : fs::directory_iterator(test::plugin_dir()))
    if (entry.path().filename().string().rfind("mtled-needle-", 0) != 0)
      fs::create_symlink(entry.path(), folder / entry.path().filename());
  const std::string env = "MTLED_PLUGIN_PATH=" + folder.string();

  const fs::path out = folder.parent_path() / "out";
  auto result = test::run_mtled({"run", kSmallCube.string(), "-o", out.string()}, {env});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json loaded = test::read_json(out / "summary.json")["plugins_loaded"];
  EXPECT_EQ(loaded.size(), 6u) << loaded.dump();
  for (const auto& file : loaded) EXPECT_EQ(file.get<std::string>().find("needle"), std::string::npos);

  const auto with_needle = variant("needle-missing", [](json& s) {
    s["needle"] = {{"type", "kinematic"}, {"entry", {0.005, 0.005, 0.01}}, {"depth", 0.003}};
  });
  result = test::run_mtled({"run", with_needle.string(), "-o", (out / "needle").string()}, {env});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, "/needle/type: unknown needle \"kinematic\"");
  expect_contains(result.output, folder.string());
}

TEST(Cli, AnAbiMismatchedPluginIsRefused) {
  const auto file = variant("abi", [](json& s) { s["materials"][0] = {{"type", "abi_mismatch"}}; });
  const auto result = test::run_mtled(
      {"validate", file.string(), "--plugin-path", MTLED_TEST_BAD_PLUGIN_DIR "/abi"});
  EXPECT_EQ(result.exit_code, 2);
  expect_contains(result.output, "built for mtled ABI version 999");
}

TEST(Cli, APluginThatThrowsWhileBeingBuiltExitsTwo) {
  const auto file = variant("throws", [](json& s) { s["materials"][0] = {{"type", "throws_when_built"}}; });
  const fs::path out = file.parent_path() / "out";
  const auto result = test::run_mtled(
      {"run", file.string(), "-o", out.string(), "--plugin-path", MTLED_TEST_BAD_PLUGIN_DIR "/throws"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, "scene.json:");
  expect_contains(result.output, "/materials/0: material \"throws_when_built\" failed while being built");
  const json summary = test::read_json(out / "summary.json");
  EXPECT_EQ(summary["status"], "invalid_input");
  EXPECT_FALSE(fs::exists(out / "result.vtu"));
}

// A time step ten times the stable one grows without bound within a few steps. The run must stop with exit 3,
// say where in summary.json and keep the last good state, and write nothing that looks like a result.
// With the stable-step monitor on, the step is refused at step 1, before anything moves; with it off, the
// blow-up itself is caught.
void expect_detected_blow_up(const std::string& name, const json& integrator, bool stable_step_monitor) {
  const auto file = variant(name, [&](json& s) {
    s["integrator"] = integrator;
    s["monitors"] = stable_step_monitor ? json{{"stable_step", "stop"}} : json{{"stable_step_every_steps", 0}};
  });
  const json summary = run_expecting_unstable_stop(file);
  const json& d = summary["diagnostic"];
  if (stable_step_monitor) {
    EXPECT_EQ(d["what"], "time_step_above_stable") << d.dump();
    EXPECT_EQ(d["step"].get<long>(), 1);
    expect_contains(d["detail"].get<std::string>(), "/integrator/time_step_factor");
  } else {
    // Whichever monitor sees it first: the energy growth, an inverted integration point, a non-finite value.
    EXPECT_TRUE(d["what"] == "energy_growth" || d["what"] == "inverted_material" || d["what"] == "non_finite")
        << d.dump();
    EXPECT_GT(d["step"].get<long>(), 0);
    EXPECT_LT(d["step"].get<long>(), 50) << "a factor of 10 should be caught within a few dozen steps";
  }
  EXPECT_FALSE(d["where"].empty());
  EXPECT_TRUE(d["where"][0].contains("coordinates_m")) << d.dump();
  EXPECT_TRUE(fs::exists(file.parent_path() / "out" / "last_good_state.vtu"));
}

TEST(Cli, TimeStepTenTimesTheStableOneIsDetected) {
  const json relaxation = {{"type", "dynamic_relaxation"}, {"load_steps", 100}, {"tolerance", 1e-5}, {"time_step_factor", 10.0}};
  const json dynamics = {{"type", "central_difference"}, {"duration", 0.3}, {"load_time", 0.2}, {"damping", 60.0},
                         {"time_step_factor", 10.0}};
  for (const bool monitor : {true, false}) {
    const std::string suffix = monitor ? "" : "-no-stable-step-monitor";
    expect_detected_blow_up("dr-factor-10" + suffix, relaxation, monitor);
    expect_detected_blow_up("cd-factor-10" + suffix, dynamics, monitor);
  }
}

// A run into a folder an unstable run left its last good state in: the folder then holds one run's outputs, so the
// old state goes (a viewer opening it beside the new result.vtu would show a failure that did not happen).
TEST(Cli, ASuccessfulRunClearsALastGoodStateLeftByAnEarlierOne) {
  const fs::path out = test::scratch_dir("cli-rerun") / "out";
  const auto unstable = test::run_mtled({"run", kSmallCube.string(), "-o", out.string(), "--no-progress", "--set",
                                         "/integrator/time_step_factor=10", "--set", "/monitors/stable_step=\"stop\""});
  ASSERT_EQ(unstable.exit_code, 3) << unstable.output;
  ASSERT_TRUE(fs::exists(out / "last_good_state.vtu"));
  const auto ok = test::run_mtled({"run", kSmallCube.string(), "-o", out.string(), "--no-progress"});
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_TRUE(fs::exists(out / "result.vtu"));
  EXPECT_FALSE(fs::exists(out / "last_good_state.vtu"));
}

// A compression of 40% applied in two load steps moves the top face 2 mm a step, more than the cloud's mesh size
// (1.93 mm: 335 nodes in the 10 mm cube): the tets under it invert while the ramp runs. The stop names the ramp's
// setting and how to slow it, and the same compression over 100 load steps (0.04 mm a step) runs through. Central
// differences alike: loaded over 0.3 ms (about 5 steps of 67 us) it inverts and says to raise load_time; over 0.2 s
// it runs through.
void expect_ramp_advice(const std::string& name, const json& fast, const json& slow, const std::string& advice) {
  const auto compressed = [](const json& integrator) {
    return [integrator](json& s) {
      s["boundaries"][1]["displacement"] = json::array({0.0, 0.0, -0.004});
      s["integrator"] = integrator;
    };
  };
  const json d = run_expecting_unstable_stop(variant(name + "-too-fast", compressed(fast)))["diagnostic"];
  EXPECT_EQ(d["what"], "inverted_material") << d.dump();
  expect_contains(d["detail"].get<std::string>(), advice);

  const auto slow_file = variant(name + "-slow", compressed(slow));
  const auto result = test::run_mtled({"run", slow_file.string(), "-o", (slow_file.parent_path() / "out").string()});
  EXPECT_EQ(result.exit_code, 0) << result.output;
}

TEST(Cli, AnInversionWhileLoadingNamesTheRampToSlow) {
  const json relaxation = {{"type", "dynamic_relaxation"}, {"tolerance", 1e-5}};
  json fast = relaxation, slow = relaxation;
  fast["load_steps"] = 2;
  slow["load_steps"] = 100;
  expect_ramp_advice("dr", fast, slow,
                     "after 1 of /integrator/load_steps = 2), whose steps may outrun the body: raise load_steps (for "
                     "example to 4");
  const json dynamics = {{"type", "central_difference"}, {"damping", 60.0}};
  fast = dynamics;
  slow = dynamics;
  fast["duration"] = 0.01;
  fast["load_time"] = 0.0003;
  slow["duration"] = 0.3;
  slow["load_time"] = 0.2;
  expect_ramp_advice("cd", fast, slow,
                     "of /integrator/load_time = 0.0003 s), whose steps may outrun the body: raise "
                     "load_time (for example to 0.0006 s");
}

// A slower blow-up (a factor of 4) under a load of 10 nm: each step multiplies the unstable mode's amplitude by
// a few, so it takes a couple of dozen steps to invert a tet. The kinetic energy passes ten times the work the
// prescribed motion has done long before: the energy monitor stops the run first. (The stable-step monitor,
// which would refuse the step at step 1, is turned off to test the energy monitor on its own.)
TEST(Cli, TheEnergyMonitorCatchesAGrowingModeBeforeItInvertsAnything) {
  const auto file = variant("energy-growth", [](json& s) {
    s["integrator"] = {{"type", "central_difference"}, {"duration", 0.3}, {"load_time", 0.2}, {"damping", 60.0},
                       {"time_step_factor", 4.0}};
    s["boundaries"][1]["displacement"] = {0.0, 0.0, -1e-8};
    s["monitors"] = {{"stable_step_every_steps", 0}};
  });
  const fs::path out = file.parent_path() / "out";
  const auto result = test::run_mtled({"run", file.string(), "-o", out.string()});
  ASSERT_EQ(result.exit_code, 3) << result.output;
  const json summary = test::read_json(out / "summary.json");
  EXPECT_EQ(summary["diagnostic"]["what"], "energy_growth") << summary["diagnostic"].dump();
  expect_contains(summary["diagnostic"]["detail"].get<std::string>(), "reduce the time-step factor");
  // The same scene at the default factor runs to the end.
  const auto stable = variant("energy-stable", [](json& s) {
    s["integrator"] = {{"type", "central_difference"}, {"duration", 0.3}, {"load_time", 0.2}, {"damping", 60.0}};
    s["boundaries"][1]["displacement"] = {0.0, 0.0, -1e-8};
  });
  EXPECT_EQ(test::run_mtled({"run", stable.string(), "-o", (stable.parent_path() / "out").string()}).exit_code, 0);
}

// Dynamic relaxation that runs out of steps is not a result: exit 3, "not_converged", and a detail that says
// which limit to raise (while the load is still being applied there is no error estimate to quote).
TEST(Cli, RelaxationThatRunsOutOfStepsIsReportedNotWritten) {
  const auto check = [](const std::string& name, const json& integrator, const std::string& detail) {
    const auto file = variant(name, [&](json& s) { s["integrator"] = integrator; });
    const fs::path out = file.parent_path() / "out";
    const auto result = test::run_mtled({"run", file.string(), "-o", out.string()});
    ASSERT_EQ(result.exit_code, 3) << result.output;
    const json summary = test::read_json(out / "summary.json");
    EXPECT_EQ(summary["status"], "unstable");
    EXPECT_EQ(summary["diagnostic"]["what"], "not_converged") << summary["diagnostic"].dump();
    expect_contains(summary["diagnostic"]["detail"].get<std::string>(), detail);
    EXPECT_FALSE(fs::exists(out / "result.vtu"));
  };
  check("dr-still-loading", {{"type", "dynamic_relaxation"}, {"load_steps", 100}, {"max_steps", 40}},
        "while still applying the load (step 40 of /integrator/load_steps = 100)");
  check("dr-not-converged",
        {{"type", "dynamic_relaxation"}, {"load_steps", 100}, {"max_steps", 120}, {"tolerance", 1e-12}},
        "did not reach the steady state in 120 steps");
}

// reactions.csv under dynamic relaxation holds the relaxed states: with four relaxed increments on the smooth
// load curve, the rows sit at exactly a quarter, half, three quarters and all of the load (not at the curve's
// values at those points of the ramp: 0.10 at a quarter). The first row equals a run compressed a quarter as far
// (the uniaxial compression is path independent), to the relaxations' tolerance (1e-5 of the displacement).
TEST(Cli, ReactionsAreWrittenAtEachRelaxedLoad) {
  auto top_rows = [](const fs::path& out) {
    std::vector<double> fz;
    std::istringstream text(test::read_text(out / "reactions.csv"));
    std::string line;
    while (std::getline(text, line))
      if (line.find(",top,") != std::string::npos) fz.push_back(std::stod(line.substr(line.rfind(',') + 1)));
    return fz;
  };
  auto run = [](const std::string& name, const std::function<void(json&)>& change) {
    const auto file = variant(name, change);
    const fs::path out = file.parent_path() / "out";
    const auto result = test::run_mtled({"run", file.string(), "-o", out.string()});
    EXPECT_EQ(result.exit_code, 0) << result.output;
    return out;
  };
  const fs::path two = run("relaxed-increments-4", [](json& s) { s["integrator"]["relaxed_increments"] = 4; });
  const std::vector<double> rows = top_rows(two);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_TRUE(fs::exists(two / "reactions_transient.csv"));
  expect_contains(test::read_text(two / "reactions_transient.csv"), "time_s,set,transient_fx_N,transient_fy_N,transient_fz_N");
  const fs::path half = run("quarter-compression", [](json& s) { s["boundaries"][1]["displacement"] = {0, 0, -0.00025}; });
  const std::vector<double> half_rows = top_rows(half);
  ASSERT_EQ(half_rows.size(), 1u);
  EXPECT_NEAR(rows[0], half_rows[0], 1e-4 * std::abs(half_rows[0]));
  const json summary = test::read_json(two / "summary.json");
  EXPECT_NEAR(rows[3], summary["final_reactions_N"]["top"][2].get<double>(), 1e-9 * std::abs(rows[3]))
      << summary["final_reactions_N"].dump();
}

// A boundary condition that pushes the three nodes at the top's centre 9 mm into the 10 mm cube: every
// integration point's J stays positive, but the displacement field turns inside out between them (J -0.28 inside a
// tet at step 200, measured, where its integration point has J 0.59). With /monitors/inversion = "stop" (the default)
// the run ends unstable naming where and the driver that pushes; "warn" warns and records the folded tets in
// summary.json. The plain compression folds nothing.
TEST(Cli, MaterialFoldedBetweenIntegrationPointsIsReported) {
  const auto pushed = [](const std::string& action) {
    return variant("fold-" + action, [&](json& s) {
      s["boundaries"] = json::array({{{"type", "fixed"}, {"name", "bottom"}, {"nodes", {{"group", "z0"}}}},
                                     {{"type", "prescribed_displacement"},
                                      {"name", "pushed"},
                                      {"nodes", {{"sphere", {{"center", {0.005, 0.005, 0.01}}, {"radius", 0.0012}}}}},
                                      {"displacement", {0, 0, -0.009}}}});
      s["integrator"] = {{"type", "dynamic_relaxation"}, {"load_steps", 300}, {"tolerance", 1e-5}};
      s["monitors"] = {{"inversion", action}};
    });
  };
  auto file = pushed("stop");
  json summary = run_expecting_unstable_stop(file);
  EXPECT_EQ(summary["diagnostic"]["what"], "inverted_between_points") << summary["diagnostic"].dump();
  EXPECT_TRUE(summary["diagnostic"]["where"][0].contains("node")) << summary["diagnostic"].dump();
  expect_contains(summary["diagnostic"]["detail"].get<std::string>(), "the displacement field's J down to -");
  expect_contains(summary["diagnostic"]["detail"].get<std::string>(), "a boundary condition pushes single nodes");

  file = pushed("warn");
  auto result = test::run_mtled({"run", file.string(), "-o", (file.parent_path() / "out").string()});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  expect_contains(result.output, "background tets folded away from the needle");
  summary = test::read_json(file.parent_path() / "out" / "summary.json");
  EXPECT_GT(summary["monitors"]["inversion"]["inverted_tets"].get<long>(), 0) << summary["monitors"].dump();
  EXPECT_LT(summary["monitors"]["inversion"]["smallest_volume_ratio"].get<double>(), 0.0);

  const fs::path plain = variant("fold-none", [](json&) {});
  result = test::run_mtled({"run", plain.string(), "-o", (plain.parent_path() / "out").string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  summary = test::read_json(plain.parent_path() / "out" / "summary.json");
  EXPECT_EQ(summary["monitors"]["inversion"]["inverted_tets"].get<long>(), 0);
  EXPECT_GT(summary["monitors"]["inversion"]["smallest_volume_ratio"].get<double>(), 0.5);
}

// The stability study's jittered cube (1,541 nodes, interior nodes moved by up to 0.3 edge lengths: 59 slivers, radius
// ratio down to 1e-4) relaxed to stretch 0.8: during the load ramp a sliver's corners turn over as soon as the field
// departs from an affine one by the sliver's thickness, while the field inside it stays whole (measured: 2 tets at
// most, J >= 0.97 inside them). They are bent, not folds, so the default "stop" lets the run end at the exact top
// force; the pushed nodes above still stop.
TEST(Cli, SliversTurningOverInARelaxationsTransientDoNotStopTheRun) {
  const fs::path scene = test::source_dir() / "share/scenes/uniaxial_cube_neohookean.json";
  const fs::path out = test::scratch_dir("cli-slivers") / "out";
  const auto result = test::run_mtled({"run", scene.string(), "-o", out.string(), "--no-progress", "--set",
                                       "/mesh/target_nodes=1500", "--set", "/mesh/jitter=0.3", "--set",
                                       "/integrator/load_steps=500", "--set", "/integrator/tolerance=1e-7"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json summary = test::read_json(out / "summary.json");
  EXPECT_LT(summary["mesh"]["min_radius_ratio"].get<double>(), kSliverRadiusRatio);
  const json& inversion = summary["monitors"]["inversion"];
  EXPECT_EQ(inversion["action"], "stop");
  EXPECT_GT(inversion["bent_tets"].get<long>(), 0) << inversion.dump();  // the transient this test is about
  EXPECT_LT(inversion["smallest_volume_ratio"].get<double>(), 0.0) << inversion.dump();
  // The exact solution is homogeneous with J near 1 (nu = 0.49): the field inside the turned-over slivers stays near
  // it, far from a fold.
  EXPECT_GT(inversion["bent_smallest_jacobian"].get<double>(), 0.5) << inversion.dump();
  EXPECT_EQ(inversion["inverted_tets"].get<long>(), 0) << inversion.dump();
  // The exact homogeneous solution for this cube (scripts/uniaxial_exact.py; the stability study's reference).
  const double exact = -0.0758180765;
  EXPECT_NEAR(summary["final_reactions_N"]["top"][2].get<double>(), exact, 1e-6 * std::abs(exact));
}

// The semi-confined compression's free side rolls over its bonded rims onto the platens: within a tet or two of a rim
// the field turns further than the tets' straight edges follow, and some tets' corners give a negative volume while
// the field's J inside them stays positive (at 3 mm, 2 tets, J >= 0.89 inside, a corner volume of -0.55 times the
// tet's, measured). That is no fold: the shipped scene, whose fold check is the default "stop", relaxes to 20% on a
// 3 mm cloud and reports those tets as bent.
TEST(Cli, TetsBentAtARolledRimDoNotStopTheRunWhereTheFieldStaysWhole) {
  const fs::path scene = test::source_dir() / "share/scenes/compression_semiconfined.json";
  ASSERT_FALSE(test::read_json(scene).contains("monitors")) << "the shipped scene runs under the default \"stop\"";
  const fs::path out = test::scratch_dir("cli-bent") / "out";
  const auto result =
      test::run_mtled({"run", scene.string(), "-o", out.string(), "--no-progress", "--set", "/mesh/mesh_size=0.003"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json inversion = test::read_json(out / "summary.json")["monitors"]["inversion"];
  EXPECT_EQ(inversion["action"], "stop");
  EXPECT_EQ(inversion["inverted_tets"].get<long>(), 0) << inversion.dump();
  EXPECT_GT(inversion["bent_tets"].get<long>(), 0) << inversion.dump();
  EXPECT_LT(inversion["smallest_volume_ratio"].get<double>(), 0.0) << inversion.dump();
  EXPECT_GT(inversion["bent_smallest_jacobian"].get<double>(), 0.0) << inversion.dump();
}

// The check knows the needle: an 8 mm insertion into a 10 mm gel cylinder folds tets around the needle's path (2 cut
// tets measured) and runs to the end under the default "stop"; a sphere of nodes pushed 6 mm into it 4 mm beside the
// axis, outside the needle's zone, folds the material (the field's J -1.0 inside a tet at step 400, measured; 5 mm
// only bends tets, the field's J staying above 0.57) and stops the run. The levers for a fold the needle's drag makes
// are pinned by NeedleDragLimit.
TEST(Cli, AFoldAwayFromTheNeedleStopsTheRunWhereTheNeedleCutsDoNot) {
  const fs::path folder = test::scratch_dir("cli-fold-needle");
  const json needle = {{"type", "kinematic"}, {"diameter", 0.0016}, {"entry", {0.0, 0.0, 0.01}},
                       {"direction", {0, 0, -1}}, {"depth", 0.008}, {"driven", "nodes_near_axis"}};
  json scene = test::gel_cylinder_scene(0.01, needle);
  test::write_text(folder / "needle.json", scene.dump(2));
  scene["boundaries"].push_back({{"type", "prescribed_displacement"},
                                 {"name", "pushed"},
                                 {"nodes", {{"sphere", {{"center", {0.004, 0.0, 0.01}}, {"radius", 0.0015}}}}},
                                 {"displacement", {0, 0, -0.006}}});
  test::write_text(folder / "pushed.json", scene.dump(2));

  auto result = test::run_mtled({"run", (folder / "needle.json").string(), "-o", (folder / "needle").string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  json summary = test::read_json(folder / "needle" / "summary.json");
  EXPECT_EQ(summary["monitors"]["inversion"]["action"], "stop");
  EXPECT_EQ(summary["monitors"]["inversion"]["inverted_tets"].get<long>(), 0) << summary["monitors"].dump();
  EXPECT_GT(summary["monitors"]["inversion"]["cut_tets"].get<long>(), 0) << summary["monitors"].dump();

  result = test::run_mtled({"run", (folder / "pushed.json").string(), "-o", (folder / "pushed").string()});
  EXPECT_EQ(result.exit_code, 3) << result.output;
  summary = test::read_json(folder / "pushed" / "summary.json");
  EXPECT_EQ(summary["diagnostic"]["what"], "inverted_between_points") << summary["diagnostic"].dump();
  EXPECT_GT(summary["monitors"]["inversion"]["inverted_tets"].get<long>(), 0);
  // The folded node lies outside the needle's zone: farther from the axis than the needle and its supports reach.
  const json& where = summary["diagnostic"]["where"][0]["coordinates_m"];
  EXPECT_GT(std::hypot(where[0].get<double>(), where[1].get<double>()), 0.003) << where.dump();
  // The message says where the fold is against the needle and the lever that applies: the pushed nodes are vertices
  // of the folded tets, so the boundary condition that pushes them, not the needle's drag; summary.json keeps the
  // depth and force the needle reached, and last_good_state.vtu marks the folded tets.
  const std::string detail = summary["diagnostic"]["detail"].get<std::string>();
  for (const char* part : {"at a needle depth of", "mm from the needle's axis", "mm under its entry",
                           "a boundary condition pushes single nodes", "cell field \"folded\""})
    expect_contains(detail, part);
  EXPECT_EQ(detail.find("/needle/"), std::string::npos) << detail;
  EXPECT_GT(summary["needle"]["final_depth_m"].get<double>(), 0.0) << summary.dump();
  EXPECT_LE(summary["needle"]["final_depth_m"].get<double>(), 0.008);
  expect_contains(test::read_text(folder / "pushed" / "last_good_state.vtu"), "Name=\"folded\"");
}

// A mesh refined along the needle (/mesh/refine_along_needle) takes the segment from the scene's needle section,
// through the needle plugin: `mtled mesh` writes the same mesh as with the needle's entry and tip as refine_from and
// refine_to, and a scene without a needle is refused, naming the setting.
TEST(Cli, AMeshRefinedAlongTheNeedleIsTheMeshRefinedAlongItsEntryAndTip) {
  const fs::path folder = test::scratch_dir("cli-refine-along-needle");
  const json needle = {
      {"type", "kinematic"}, {"entry", {0.001, 0.0, 0.01}}, {"direction", {0, 0, -1}}, {"depth", 0.006}};
  json along = test::gel_cylinder_scene(0.01, needle);
  along["mesh"]["refine_along_needle"] = true;
  along["mesh"]["refine_size"] = 0.0007;
  json ends = along;
  ends["mesh"].erase("refine_along_needle");
  ends["mesh"]["refine_from"] = {0.001, 0.0, 0.01};
  ends["mesh"]["refine_to"] = {0.001, 0.0, 0.004};
  json without = along;
  without.erase("needle");
  std::map<std::string, std::string> written;
  for (const auto& [name, scene] : {std::pair{"along", along}, std::pair{"ends", ends}}) {
    test::write_text(folder / (std::string(name) + ".json"), scene.dump(2));
    const fs::path inp = folder / (std::string(name) + ".inp");
    const auto result =
        test::run_mtled({"mesh", (folder / (std::string(name) + ".json")).string(), "-o", inp.string()});
    ASSERT_EQ(result.exit_code, 0) << result.output;
    written[name] = test::read_text(inp);
  }
  EXPECT_EQ(written["along"], written["ends"]);
  test::write_text(folder / "without.json", without.dump(2));
  const auto refused = test::run_mtled({"mesh", (folder / "without.json").string(), "-o", (folder / "w.inp").string()});
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  expect_contains(refused.output, "/mesh/refine_along_needle");
}

TEST(Cli, OverridesAndUnknownCommands) {
  const fs::path out = test::scratch_dir("cli-set") / "out";
  auto result = test::run_mtled({"run", kSmallCube.string(), "-o", out.string(), "--set", "/materials/0/mu=-5"});
  EXPECT_EQ(result.exit_code, 2);
  expect_contains(result.output, "--set /materials/0/mu: -5 is out of range");
  result = test::run_mtled({"frobnicate"});
  EXPECT_EQ(result.exit_code, 2);
}

}  // namespace
}  // namespace mtled
