// One scene on several MPI ranks (the mpi backend, docs/mpi.md) against the same scene on one process: the same step
// count and the same displacements up to the order of the force sums (NRMSE <= 1e-12), the same bits on a repeat,
// and a failing rank that ends the whole run; a study whose runs are spread over ranks gives the serial study's
// report. Run through mpirun (label mpi; skipped where mpirun is missing).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <regex>

#include "test_support.hpp"

namespace fs = std::filesystem;

namespace mtled {
namespace {

// Open MPI refuses root unless told; CI runs as root in a container.
const std::vector<std::string> kEnvironment = {"OMPI_ALLOW_RUN_AS_ROOT=1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1",
                                               "OMPI_MCA_rmaps_base_oversubscribe=1"};

// A hang would stall CI: every multi-rank run is killed after a minute.
std::vector<std::string> launcher(int ranks) {
  return {"timeout", "-s", "KILL", "60", "mpirun", "-np", std::to_string(ranks)};
}

bool have_mpirun() { return std::system("command -v mpirun > /dev/null 2>&1") == 0; }

fs::path folder(const std::string& name) {
  const fs::path dir = fs::path(MTLED_TEST_BINARY_DIR) / "test_output" / "mpi" / name;
  fs::remove_all(dir);
  fs::create_directories(dir.parent_path());
  return dir;
}

// The gel cylinder with the kinematic needle to 5 mm: captures and the shaft's constraints cross the partition.
fs::path needle_scene(const std::string& name) {
  const json needle = {{"type", "kinematic"}, {"diameter", 1.6e-3}, {"entry", {0.0, 0.0, 8e-3}},
                       {"direction", {0, 0, -1}}, {"depth", 5e-3}, {"deformation_coefficient", 0.4}};
  // One file per test: ctest runs tests side by side.
  const fs::path file = fs::path(MTLED_TEST_BINARY_DIR) / "test_output" / "mpi" / (name + ".json");
  test::write_text(file, test::gel_cylinder_scene(8e-3, needle).dump(2));
  return file;
}
fs::path cube_scene() { return fs::path(MTLED_TEST_SOURCE_DIR) / "tests/scenes/data/small_cube.json"; }

test::CommandResult run(const fs::path& scene, const fs::path& out, int ranks,
                        const std::vector<std::string>& environment = {}) {
  std::vector<std::string> arguments = {"run", scene.string(), "-o", out.string(), "--threads", "1", "--no-progress"};
  std::vector<std::string> env = kEnvironment;
  env.insert(env.end(), environment.begin(), environment.end());
  return test::run_mtled(arguments, env, ranks > 0 ? launcher(ranks) : std::vector<std::string>{});
}

double largest_nrmse(const fs::path& a, const fs::path& b) {
  const auto compared = test::run_mtled({"compare", a.string(), b.string(), "--json"});
  EXPECT_EQ(compared.exit_code, 0) << compared.output;
  const json nrmse = json::parse(compared.output)["nrmse"];
  return std::max({nrmse["ux"].get<double>(), nrmse["uy"].get<double>(), nrmse["uz"].get<double>()});
}

// The (time, file) of each snapshot that series.pvd lists.
std::vector<std::pair<double, std::string>> snapshots(const fs::path& series) {
  const std::regex entry(R"re(<DataSet timestep="([^"]+)" file="([^"]+)"/>)re");
  std::vector<std::pair<double, std::string>> listed;
  const std::string text = test::read_text(series);
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it)
    listed.emplace_back(std::stod((*it)[1].str()), (*it)[2].str());
  return listed;
}

class MpiRun : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    if (!have_mpirun()) GTEST_SKIP() << "mpirun is not installed";
  }
};

// The bound: the ranks only change the order in which each node's force contributions are added (round-off,
// 1e-16 relative per sum), which the dynamic relaxation's 300 to 3,000 steps carry to about 1e-13 at most.
TEST_P(MpiRun, TheNeedleInsertionIsTheOneProcessAnswer) {
  const int ranks = GetParam();
  const std::string name = "needle_on_" + std::to_string(ranks);
  const fs::path scene = needle_scene(name);
  // Snapshots every 40 steps: rank 0's writer reads the whole displacement then, and the other ranks, which do not
  // write, must gather it with it.
  json document = json::parse(test::read_text(scene));
  document["output"] = {{"every_steps", 40}};
  test::write_text(scene, document.dump(2));
  const fs::path one = folder(name + "_serial"), several = folder(name);
  const auto serial = run(scene, one, 0);
  ASSERT_EQ(serial.exit_code, 0) << serial.output;
  const auto parallel = run(scene, several, ranks);
  ASSERT_EQ(parallel.exit_code, 0) << parallel.output;
  const json a = test::read_json(one / "summary.json"), b = test::read_json(several / "summary.json");
  EXPECT_EQ(b["backend"]["type"], "mpi");
  EXPECT_EQ(b["backend"]["ranks"], ranks);
  const json& partition = b["backend"]["partition"];
  ASSERT_EQ(partition["integration_points"].size(), static_cast<std::size_t>(ranks));
  // Each rank computes its boundary points (whose supports reach other ranks' nodes) before it sends, and the rest
  // of its points while the messages travel: even a third of this 2,300-point cloud has an interior.
  for (int r = 0; r < ranks; ++r) {
    const std::int64_t points = partition["integration_points"][r], boundary = partition["boundary_points"][r],
                       first = partition["points_before_sending"][r];
    EXPECT_GT(boundary, 0) << "rank " << r;
    EXPECT_GE(first, boundary) << "rank " << r;
    EXPECT_LT(first, points) << "rank " << r << ": no interior computed while the halo travels";
  }
  EXPECT_EQ(a["steps"], b["steps"]);
  const double fa = a["needle"]["final_force_N"], fb = b["needle"]["final_force_N"];
  EXPECT_GT(fa, 0.0);
  EXPECT_NEAR(fb, fa, 1e-12 * fa);
  EXPECT_LE(largest_nrmse(several, one), 1e-12);
  // Each step brings a rank its ghost nodes' displacements only; the whole displacement is gathered for the
  // snapshots (every 40 steps), the fold checks (every 100), the stable-step estimates (steps 1 and 2,000) and the
  // end; the needle's reads (a few dozen nodes around its tip and path) are gathered before each update.
  const long steps = b["steps"];
  const json& gathers = b["backend"]["displacement_gathers"];
  EXPECT_LE(gathers["whole"].get<long>(), steps / 40 + steps / 100 + 3) << gathers.dump();
  EXPECT_GT(gathers["driver_nodes"].get<long>(), 0) << gathers.dump();
  EXPECT_LT(gathers["driver_nodes"].get<long>(), steps * b["nodes"].get<long>() / 4) << gathers.dump();
  EXPECT_LT(partition["ghost_bytes_per_step"].get<long>(), partition["whole_gather_bytes"].get<long>());
  EXPECT_GT(partition["ghost_bytes_per_step"].get<long>(), 0);
  // The snapshots are the one process's too: the same steps, at the same times. (A time follows the stable step,
  // which the ranks estimate to round-off as well; series.pvd prints 10 digits, so two times 1e-13 apart may print
  // one unit apart in the last: up to 1e-9 of the time.)
  const auto parallel_snapshots = snapshots(several / "series.pvd"), serial_snapshots = snapshots(one / "series.pvd");
  ASSERT_EQ(parallel_snapshots.size(), serial_snapshots.size());
  ASSERT_GT(serial_snapshots.size(), 2u);
  for (std::size_t i = 0; i < serial_snapshots.size(); ++i) {
    EXPECT_EQ(parallel_snapshots[i].second, serial_snapshots[i].second);
    EXPECT_NEAR(parallel_snapshots[i].first, serial_snapshots[i].first, 2e-9 * serial_snapshots[i].first)
        << serial_snapshots[i].second;
  }
}

TEST_P(MpiRun, TheCubeIsTheOneProcessAnswerAndTheSameOnARepeat) {
  const int ranks = GetParam();
  const std::string name = "cube_on_" + std::to_string(ranks);
  const fs::path one = folder(name + "_serial"), several = folder(name), again = folder(name + "_again");
  ASSERT_EQ(run(cube_scene(), one, 0).exit_code, 0);
  const auto first = run(cube_scene(), several, ranks);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  ASSERT_EQ(run(cube_scene(), again, ranks).exit_code, 0);
  EXPECT_EQ(test::read_json(one / "summary.json")["steps"], test::read_json(several / "summary.json")["steps"]);
  EXPECT_LE(largest_nrmse(several, one), 1e-12);
  // Each node's contributions are added in rank order whatever order the messages arrive in.
  EXPECT_EQ(test::read_text(several / "result.vtu"), test::read_text(again / "result.vtu"));
  EXPECT_EQ(test::read_text(several / "reactions.csv"), test::read_text(again / "reactions.csv"));
}

// The averaged dilatation (nodal_average) is divided too: each rank evaluates its own points and the layers of
// other ranks' points their averages reach. Bound as above.
TEST_P(MpiRun, TheAveragedDilatationIsDividedAndIsTheOneProcessAnswer) {
  const int ranks = GetParam();
  const std::string name = "averaged_on_" + std::to_string(ranks);
  const fs::path file = needle_scene(name);
  json scene = json::parse(test::read_text(file));
  scene["volumetric"] = {{"type", "nodal_average"}};
  test::write_text(file, scene.dump(2));
  const fs::path one = folder(name + "_serial"), several = folder(name);
  const auto serial = run(file, one, 0);
  ASSERT_EQ(serial.exit_code, 0) << serial.output;
  const auto parallel = run(file, several, ranks);
  ASSERT_EQ(parallel.exit_code, 0) << parallel.output;
  EXPECT_EQ(parallel.output.find("whole on every rank"), std::string::npos) << parallel.output;
  const json a = test::read_json(one / "summary.json"), b = test::read_json(several / "summary.json");
  EXPECT_FALSE(b["backend"].contains("forces")) << b["backend"].dump();
  EXPECT_EQ(a["steps"], b["steps"]);
  const double fa = a["needle"]["final_force_N"], fb = b["needle"]["final_force_N"];
  EXPECT_NEAR(fb, fa, 1e-12 * fa);
  EXPECT_LE(largest_nrmse(several, one), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Ranks, MpiRun, ::testing::Values(2, 3));

// A run every rank finds unstable (the cube at ten times its stable step inverts a point at step 5): the ranks
// gather the last good state, which only rank 0 writes, and end alike with exit 3, never a hang.
TEST(MpiFailure, AnUnstableRunWritesTheLastGoodStateLikeOneProcess) {
  if (!have_mpirun()) GTEST_SKIP() << "mpirun is not installed";
  const fs::path one = folder("unstable_serial"), several = folder("unstable");
  const std::vector<std::string> unstable = {"--set", "/integrator/time_step_factor=10", "--set",
                                             "/monitors/stable_step_every_steps=0"};
  auto arguments = [&](const fs::path& out) {
    std::vector<std::string> a = {"run", cube_scene().string(), "-o", out.string(), "--threads", "1", "--no-progress"};
    a.insert(a.end(), unstable.begin(), unstable.end());
    return a;
  };
  const auto serial = test::run_mtled(arguments(one), kEnvironment);
  ASSERT_EQ(serial.exit_code, 3) << serial.output;
  const auto parallel = test::run_mtled(arguments(several), kEnvironment, launcher(2));
  ASSERT_EQ(parallel.exit_code, 3) << parallel.output;
  const json a = test::read_json(one / "summary.json"), b = test::read_json(several / "summary.json");
  EXPECT_EQ(b["status"], "unstable");
  EXPECT_EQ(b["diagnostic"]["what"], a["diagnostic"]["what"]);
  EXPECT_EQ(b["diagnostic"]["step"], a["diagnostic"]["step"]);
  EXPECT_FALSE(fs::exists(several / "result.vtu"));
  // u_(n-1) (the state before the inverting step), gathered from every rank: one process's up to round-off.
  EXPECT_LE(largest_nrmse(several / "last_good_state.vtu", one / "last_good_state.vtu"), 1e-12);
}

TEST(MpiFailure, OneFailingRankEndsTheRunWithAnErrorNotAHang) {
  if (!have_mpirun()) GTEST_SKIP() << "mpirun is not installed";
  const fs::path out = folder("failure");
  const auto result = run(needle_scene("needle_failure"), out, 2, {"MTLED_TEST_FAIL_RANK=1:20"});
  EXPECT_NE(result.exit_code, 0) << result.output;
  EXPECT_NE(result.exit_code, 137) << "killed by the test's timeout: the ranks hung\n" << result.output;
  EXPECT_NE(result.output.find("rank 1 of 2: failure injected at step 20"), std::string::npos) << result.output;
  EXPECT_FALSE(fs::exists(out / "result.vtu"));
}

// Ctrl-C reaches every rank through the launcher: the run ends as one process's does, summary.json "interrupted".
TEST(MpiFailure, AnInterruptedRunSaysSo) {
  if (!have_mpirun()) GTEST_SKIP() << "mpirun is not installed";
  const fs::path out = folder("interrupted");
  const fs::path scene = fs::path(MTLED_TEST_SOURCE_DIR) / "share/scenes/needle_small_sample.json";
  const std::string log = out.string() + ".log";
  std::string script = "export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1\n";
  script += "mpirun -np 2 '" + std::string(MTLED_EXECUTABLE) + "' run '" + scene.string() + "' -o '" + out.string() +
            "' --threads 1 --no-progress > '" + log + "' 2>&1 &\npid=$!\n";
  script += "(sleep 60; kill -KILL $pid) > /dev/null 2>&1 &\nwatchdog=$!\n";  // a hang fails the test, never CI
  // Interrupt a second into the time loop (the puncture is logged at its first steps).
  script += "for i in $(seq 300); do grep -q puncture '" + log + "' && break; sleep 0.1; done\nsleep 1\n";
  script += "kill -INT $pid\nwait $pid\nstatus=$?\nkill $watchdog 2>/dev/null\nexit $status\n";
  const fs::path file = out.string() + ".sh";
  test::write_text(file, script);
  const int status = std::system(("bash '" + file.string() + "'").c_str());
  EXPECT_NE(status, 0);
  const json summary = test::read_json(out / "summary.json");
  EXPECT_EQ(summary["status"], "interrupted") << test::read_text(log);
  EXPECT_FALSE(fs::exists(out / "result.vtu"));
}

TEST(MpiBackend, NamedWithoutALauncherItSaysHowToRunIt) {
  const fs::path out = folder("no_launcher");
  const auto result = test::run_mtled({"run", cube_scene().string(), "-o", out.string(), "--backend", "mpi"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("mpirun -np N mtled run"), std::string::npos) << result.output;
}

TEST(MpiBackend, AnotherBackendOnSeveralRanksIsRefused) {
  if (!have_mpirun()) GTEST_SKIP() << "mpirun is not installed";
  const fs::path out = folder("other_backend");
  const auto result = test::run_mtled({"run", cube_scene().string(), "-o", out.string(), "--backend", "cpu"},
                                      kEnvironment, launcher(2));
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("the cpu backend runs on one process, and this run has 2 processes"), std::string::npos)
      << result.output;
}

// study.csv's columns that do not depend on when or where a run ran.
std::vector<std::string> measured_rows(const fs::path& csv) {
  const auto rows = test::read_csv(csv);
  std::vector<std::string> out;
  for (const auto& row : rows) {
    std::string kept;
    for (const char* name : {"label", "status", "exit_code", "steps", "error"}) {
      const auto at = std::find(rows[0].begin(), rows[0].end(), name) - rows[0].begin();
      kept += row.at(static_cast<std::size_t>(at)) + ";";
    }
    out.push_back(kept);
  }
  return out;
}

TEST(MpiStudy, RunsSpreadOverRanksGiveTheSerialReport) {
  if (!have_mpirun()) GTEST_SKIP() << "mpirun is not installed";
  const fs::path dir = folder("study");
  const json study = {{"scene", cube_scene().string()},
                      {"threads", 1},
                      {"metric", "nrmse"},
                      {"reference", {{"label", "dense"}, {"set", {{"/mesh/target_nodes", 500}}}}},
                      {"sweep", {{"/mesh/target_nodes", {200, 250, 300}}}}};
  test::write_text(dir / "study.json", study.dump(2));
  const auto serial = test::run_mtled({"study", (dir / "study.json").string(), "-o", (dir / "serial").string()});
  ASSERT_EQ(serial.exit_code, 0) << serial.output;
  const auto spread = test::run_mtled({"study", (dir / "study.json").string(), "-o", (dir / "ranks").string()},
                                      kEnvironment, launcher(2));
  ASSERT_EQ(spread.exit_code, 0) << spread.output;
  EXPECT_EQ(measured_rows(dir / "ranks" / "study.csv"), measured_rows(dir / "serial" / "study.csv"));
  // Each run ran alone on one process (the launcher's variables kept from the children): no "mpi" backend.
  EXPECT_EQ(test::read_json(dir / "ranks" / "runs" / "target_nodes=250" / "summary.json")["backend"]["type"], "cpu");
}

}  // namespace
}  // namespace mtled
