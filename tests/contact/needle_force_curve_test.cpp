// needle.csv under dynamic relaxation is the needle force against depth in equilibrium: each row is a state the
// relaxation reached at a held depth (/integrator/relaxed_increments), and equals the force of a run that
// stopped at that depth and relaxed there. The relaxation's transient along the way, which is not a
// force-depth curve (at the same depth it reads well above the equilibrium force while the tissue still
// moves), is kept in needle_transient.csv under its own name.
#include <gtest/gtest.h>

#include <iostream>
#include <sstream>

#include "test_support.hpp"

namespace fs = std::filesystem;

namespace mtled {
namespace {

constexpr double kHeight = 8e-3;

struct Row {
  double depth = 0.0, force = 0.0;
};

std::vector<Row> needle_rows(const fs::path& file, const std::string& force_column) {
  std::istringstream text(test::read_text(file));
  std::string line;
  std::getline(text, line);
  EXPECT_EQ(line, "time_s,depth_m," + force_column + ",phase") << file;
  std::vector<Row> rows;
  while (std::getline(text, line)) {
    std::istringstream fields(line);
    std::string time, depth, force;
    std::getline(fields, time, ',');
    std::getline(fields, depth, ',');
    std::getline(fields, force, ',');
    rows.push_back({std::stod(depth), std::stod(force)});
  }
  return rows;
}

// The small gel cylinder with the kinematic needle to `depth`, the load ramp at 50 steps per mm, relaxed at
// `increments` equally spaced depths (tolerance 1e-5, as the default scene).
fs::path run(const std::string& name, double depth, long increments) {
  json needle = {{"type", "kinematic"},   {"diameter", 1.6e-3}, {"entry", {0.0, 0.0, kHeight}},
                 {"direction", {0, 0, -1}}, {"depth", depth},     {"deformation_coefficient", 0.4}};
  json scene = test::gel_cylinder_scene(kHeight, needle);
  scene["integrator"]["load_steps"] = std::lround(50.0 * depth / 1e-3);
  scene["integrator"]["tolerance"] = 1e-5;
  scene["integrator"]["relaxed_increments"] = increments;
  const fs::path folder = test::scratch_dir("needle-force-curve-" + name);
  test::write_text(folder / "scene.json", scene.dump(2));
  const auto result = test::run_mtled({"run", (folder / "scene.json").string(), "-o", (folder / "out").string()});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return folder / "out";
}

TEST(NeedleForceCurve, EachRowEqualsTheForceOfARunRelaxedAtThatDepth) {
  const fs::path curve = run("curve", 6e-3, 3);
  const std::vector<Row> rows = needle_rows(curve / "needle.csv", "force_N");
  ASSERT_EQ(rows.size(), 3u);
  const std::vector<Row> transient = needle_rows(curve / "needle_transient.csv", "transient_force_N");
  EXPECT_GT(transient.size(), 10u);
  const json summary = test::read_json(curve / "summary.json");
  EXPECT_EQ(summary["integrator"]["relaxed_states"], 3);
  for (int k = 1; k <= 3; ++k) {
    const double depth = 2e-3 * k;
    EXPECT_NEAR(rows[k - 1].depth, depth, 1e-9);
    const json alone = test::read_json(run("depth" + std::to_string(k), depth, 1) / "summary.json");
    const double relaxed = alone["needle"]["final_force_N"].get<double>();
    ASSERT_GT(relaxed, 0.0);
    // 2%: what the curve promises (the relaxations' own tolerance, 1e-5 of the displacement, is far below).
    EXPECT_NEAR(rows[k - 1].force, relaxed, 0.02 * relaxed) << "depth " << depth;
    std::cout << "depth " << 1e3 * depth << " mm: curve " << rows[k - 1].force << " N, relaxed alone " << relaxed
              << " N, relative difference " << rows[k - 1].force / relaxed - 1.0 << "\n";
  }
  // The last row is the run's final state (needle.csv keeps 10 significant digits).
  const double final_force = summary["needle"]["final_force_N"].get<double>();
  EXPECT_NEAR(rows.back().force, final_force, 1e-9 * final_force);
}

}  // namespace
}  // namespace mtled
