// mtled compare end to end: a run against itself, exactly affine fields on different node clouds (where MLS
// interpolation with a linear basis is exact), a known scaling whose NRMSE and difference percentiles are
// worked out here from the reference run's nodes, the histogram SVG, and bad paths (exit 2 naming the path).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "mtled/analysis/compare.hpp"
#include "mtled/io/output.hpp"
#include "mtled/io/vtk_grid.hpp"
#include "test_support.hpp"
#include "xml_check.hpp"

namespace fs = std::filesystem;

namespace mtled::test {
namespace {

const fs::path kSmallCube = source_dir() / "tests/scenes/data/small_cube.json";

void expect_contains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "expected \"" << part << "\" in:\n" << text;
}

// A 10 mm cube whose every node is prescribed the affine displacement d + G X (so result.vtu holds that
// field to round-off: the constraint correction makes the interpolated displacement at constrained nodes
// equal the prescribed value), meshed with about `nodes` nodes.
fs::path affine_run(const std::string& name, const Mat3& G, const Vec3& d, int nodes,
                    const json& output = json::object()) {
  std::vector<double> gradient(9);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) gradient[static_cast<std::size_t>(3 * r + c)] = G(r, c);  // row by row
  json scene = {
      {"mesh", {{"type", "box"}, {"size", {0.01, 0.01, 0.01}}, {"target_nodes", nodes}}},
      {"shape_function", {{"type", "mls"}}},
      {"materials", {{{"type", "neo_hookean"}, {"mu", 1000}, {"D", 4.02684e-5}}}},
      {"boundaries",
       {{{"type", "prescribed_displacement"},
         {"name", "everything"},
         {"nodes", {{"box", {{"min", {-1, -1, -1}}, {"max", {1, 1, 1}}}}}},
         {"displacement", {d[0], d[1], d[2]}},
         {"gradient", gradient}}}},
      {"integrator", {{"type", "dynamic_relaxation"}, {"load_steps", 20}, {"tolerance", 1e-6}}}};
  if (!output.empty()) scene["output"] = output;
  const fs::path folder = scratch_dir("compare-" + name);
  write_text(folder / "scene.json", scene.dump(2));
  const auto result = run_mtled({"run", (folder / "scene.json").string(), "-o", (folder / "out").string(), "--threads", "1"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return folder / "out";
}

const Mat3 kG = (Mat3() << 0.05, 0.02, -0.01, 0.01, -0.03, 0.02, -0.02, 0.015, -0.08).finished();
const Vec3 kD(1e-4, -2e-4, 3e-4);

json compare_json(const fs::path& a, const fs::path& b) {
  const auto result = run_mtled({"compare", a.string(), b.string(), "--json"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return json::parse(result.output);
}

TEST(Compare, ARunAgainstItselfGivesZero) {
  const fs::path out = scratch_dir("compare-self") / "run";
  auto result = run_mtled({"run", kSmallCube.string(), "-o", out.string(), "--threads", "1"});
  ASSERT_EQ(result.exit_code, 0) << result.output;

  const json report = compare_json(out, out);
  for (const char* k : {"ux", "uy", "uz"}) {
    EXPECT_EQ(report["nrmse"][k].get<double>(), 0.0) << k;
    EXPECT_EQ(report["max_abs_difference_m"][k].get<double>(), 0.0) << k;
    EXPECT_GT(report["range_m"][k].get<double>(), 0.0) << k;
  }
  EXPECT_FALSE(report["interpolated"].get<bool>());
  EXPECT_EQ(report["nodes"]["a"], report["nodes"]["b"]);
  EXPECT_FALSE(report["definition"].get<std::string>().empty());

  // The human-readable table.
  result = run_mtled({"compare", out.string(), (out / "result.vtu").string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  for (const char* part : {"NRMSE", "ux", "uy", "uz", "same node cloud", "RMSE = sqrt(mean of squares)"})
    expect_contains(result.output, part);
}

// An affine field on two different clouds: linear-basis MLS reproduces it exactly, so what is left is
// round-off.
TEST(Compare, AnAffineFieldOnDifferentCloudsAgreesToRoundOff) {
  const fs::path coarse = affine_run("affine-coarse", kG, kD, 300);
  const fs::path fine = affine_run("affine-fine", kG, kD, 600);
  const ResultField a = read_result_vtu(coarse / "result.vtu"), b = read_result_vtu(fine / "result.vtu");
  ASSERT_NE(a.points.size(), b.points.size());
  // The runs hold the affine field itself.
  double worst = 0.0;
  for (std::size_t i = 0; i < b.points.size(); ++i)
    worst = std::max(worst, (b.displacement[i] - (kD + kG * b.points[i])).cwiseAbs().maxCoeff());
  ASSERT_LT(worst, 1e-12);

  const json report = compare_json(coarse, fine);
  EXPECT_TRUE(report["interpolated"].get<bool>());
  EXPECT_EQ(report["nodes"]["a"].get<std::size_t>(), a.points.size());
  EXPECT_EQ(report["nodes"]["b"].get<std::size_t>(), b.points.size());
  for (const char* k : {"ux", "uy", "uz"}) {
    EXPECT_LT(report["nrmse"][k].get<double>(), 1e-9) << k;
    EXPECT_LT(report["max_abs_difference_m"][k].get<double>(), 1e-12) << k;
  }
}

// The grid transfer on a field that is not a polynomial: carried from cloud A to cloud B and back to A, the
// error against the exact field falls as h^2 under refinement (MLS with a linear basis reproduces linear fields
// exactly, so its error is second order in the node spacing, as an interpolating MLS's would be). The clouds
// are jittered boxes of 10 mm; B is a different jittered cloud of about the same spacing.
TEST(Compare, TransferRoundTripOfASmoothFieldIsSecondOrder) {
  const auto field = [](const Vec3& x) {
    const double k = 200.0;  // one wavelength per 31 mm: smooth but far from linear over the box
    return Vec3(1e-4 * std::sin(k * x[0]), 1e-4 * std::cos(k * x[1]), 1e-4 * std::sin(k * x[2]) * std::cos(k * x[0]));
  };
  double previous = 0.0;
  for (const int n : {6, 12, 24}) {
    const TetMesh a = test::box_mesh(Vec3(0.01, 0.01, 0.01), n, n, n, 0.2, 3);
    const TetMesh b = test::box_mesh(Vec3(0.01, 0.01, 0.01), n + 1, n + 1, n + 1, 0.2, 4);
    std::vector<Vec3> u_a;
    for (const auto& x : a.points) u_a.push_back(field(x));
    const auto u_b = interpolate_displacements(a.points, u_a, b.points, test::catalog());
    const auto back = interpolate_displacements(b.points, u_b, a.points, test::catalog());
    double error = 0.0;
    for (std::size_t i = 0; i < a.points.size(); ++i) error = std::max(error, (back[i] - u_a[i]).cwiseAbs().maxCoeff());
    std::cout << "n = " << n << ": round-trip error " << error / 1e-4 << " of the amplitude";
    if (previous > 0.0) {
      const double order = std::log2(previous / error);
      std::cout << ", observed order " << order;
      EXPECT_GT(order, 1.7) << n;
    }
    std::cout << "\n";
    previous = error;
  }
  EXPECT_LT(previous, 1e-2 * 1e-4);  // 24 cells across: 0.5% of the amplitude, below the needle study's 1e-2 NRMSE
}

// /output/length_unit = "mm" (3D Slicer's unit): the file holds coordinates and displacements x 1000 and says
// so; mtled reads it back in metres, so the affine field is recovered and compares equal to the run in metres.
TEST(Compare, AResultInMillimetresReadsBackInMetres) {
  const fs::path metres = affine_run("unit-m", kG, kD, 300);
  const fs::path millimetres = affine_run("unit-mm", kG, kD, 300, {{"length_unit", "mm"}});
  const std::string text = read_text(millimetres / "result.vtu");
  expect_contains(text, "Name=\"LENGTH_UNIT\"");
  const ResultField field = read_result_vtu(millimetres / "result.vtu");
  const ResultField reference = read_result_vtu(metres / "result.vtu");
  ASSERT_EQ(field.points.size(), reference.points.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < field.points.size(); ++i) {
    // x 1000 then x 0.001: two roundings of coordinates up to 0.01 m (ulp 1.7e-18)
    EXPECT_LE((field.points[i] - reference.points[i]).cwiseAbs().maxCoeff(), 4e-18) << i;
    worst = std::max(worst, (field.displacement[i] - (kD + kG * field.points[i])).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-9 * 1e-3);  // the affine field to round-off of its 1e-3 m size
  const json report = compare_json(metres, millimetres);
  for (const char* name : {"ux", "uy", "uz"}) EXPECT_LT(report["nrmse"][name].get<double>(), 1e-12) << name;
  // The raw file really is in millimetres: read as a plain grid, its points are 1000 times the metres.
  const auto grid = vtk::read_vtu(mesh_readers::read_text_file(millimetres / "result.vtu", "result.vtu"), {});
  EXPECT_EQ(grid.length_unit, "mm");
  ASSERT_EQ(grid.points.size(), reference.points.size());
  EXPECT_NEAR(grid.points[7][0], 1e3 * reference.points[7][0], 1e-12);
}

// u_A = (d + G X) and u_B = 2 (d + G X): u_A - u_B = -(d + G X), so NRMSE_k = sqrt(mean of (d + G X)_k^2) /
// (max - min of 2 (d + G X)_k) over B's nodes, on the same cloud and on a different one.
TEST(Compare, AKnownScalingGivesTheNrmseWorkedOutByHand) {
  const fs::path a_same = affine_run("scaling-a", kG, kD, 300);
  const fs::path a_other = affine_run("scaling-a-other", kG, kD, 600);
  const fs::path b = affine_run("scaling-b", 2.0 * kG, 2.0 * kD, 300);
  const ResultField field = read_result_vtu(b / "result.vtu");
  Vec3 squares = Vec3::Zero(), lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& X : field.points) {
    const Vec3 u = kD + kG * X;
    squares += u.cwiseProduct(u);
    lo = lo.cwiseMin(2.0 * u);
    hi = hi.cwiseMax(2.0 * u);
  }
  const Vec3 expected = (squares / static_cast<double>(field.points.size())).cwiseSqrt().cwiseQuotient(hi - lo);

  for (const fs::path& a : {a_same, a_other}) {
    const json report = compare_json(a, b);
    EXPECT_EQ(report["interpolated"].get<bool>(), a == a_other);
    int k = 0;
    for (const char* name : {"ux", "uy", "uz"}) {
      const double nrmse = report["nrmse"][name].get<double>();
      EXPECT_NEAR(nrmse, expected[k], 1e-9 * expected[k]) << name << " from " << a;
      // The paper's literal formula (1/N outside the root) is NRMSE / sqrt(N).
      EXPECT_NEAR(report["nrmse_paper_formula"][name].get<double>(),
                  expected[k] / std::sqrt(static_cast<double>(field.points.size())), 1e-9 * expected[k]);
      ++k;
    }
    // Each reported percentile q of |u_A - u_B| = |d + G X| is a quantile by definition: at least p% of
    // B's nodes at or under it, fewer than p% strictly under it (with a round-off margin of 1e-12 m).
    const double n = static_cast<double>(field.points.size());
    for (const int percent : {50, 90, 99}) {
      const json& row = report["abs_difference_quantiles_m"][fmt::format("p{}", percent)];
      int column = 0;
      for (const char* name : {"ux", "uy", "uz", "magnitude"}) {
        const double q = row[name].get<double>();
        double at_or_under = 0, under = 0;
        for (const Vec3& X : field.points) {
          const Vec3 u = kD + kG * X;
          const double value = column < 3 ? std::abs(u[column]) : u.norm();
          at_or_under += value <= q + 1e-12;
          under += value < q - 1e-12;
        }
        EXPECT_GE(at_or_under, percent * n / 100) << name << " p" << percent << " from " << a;
        EXPECT_LT(under, percent * n / 100) << name << " p" << percent << " from " << a;
        ++column;
      }
    }
  }
}

TEST(Compare, WritesHistogramsAsWellFormedSvg) {
  const fs::path a = affine_run("histogram-a", kG, kD, 300);
  const fs::path b = affine_run("histogram-b", 2.0 * kG, 2.0 * kD, 300);
  const fs::path svg = a.parent_path() / "figures" / "differences.svg";
  const auto result = run_mtled({"compare", a.string(), b.string(), "--histogram", svg.string(), "--bins", "25"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  expect_contains(result.output, svg.string());
  ASSERT_TRUE(fs::exists(svg));
  const std::string text = read_text(svg);
  EXPECT_EQ(xml_problem(text), "");
  expect_contains(text, "<svg xmlns=\"http://www.w3.org/2000/svg\"");
  for (const char* part : {"id=\"panel0\"", "id=\"panel1\"", "id=\"panel2\"", "u_x(A) - u_x(B) (m)", "NRMSE"})
    expect_contains(text, part);
  const std::size_t nodes = read_result_vtu(b / "result.vtu").points.size();
  expect_contains(text, "(" + std::to_string(nodes) + " in all)");
}

TEST(Compare, BadPathsExitTwoNamingThePath) {
  const fs::path folder = scratch_dir("compare-bad");
  const fs::path missing = folder / "no-such-run";
  auto result = run_mtled({"compare", missing.string(), missing.string()});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, missing.string());
  expect_contains(result.output, "no such run folder");

  const fs::path empty = folder / "empty";
  fs::create_directories(empty);
  result = run_mtled({"compare", empty.string(), empty.string(), "--json"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, (empty / "result.vtu").string());

  const fs::path unstable = folder / "unstable";
  write_text(unstable / "summary.json", R"({"status": "unstable"})");
  result = run_mtled({"compare", unstable.string(), empty.string()});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, "status \"unstable\"");

  const fs::path garbage = folder / "garbage.vtu";
  write_text(garbage, "<VTKFile>\n</VTKFile>\n");
  result = run_mtled({"compare", garbage.string(), garbage.string()});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, garbage.string());

  result = run_mtled({"compare", empty.string()});
  EXPECT_EQ(result.exit_code, 2) << result.output;
}

}  // namespace
}  // namespace mtled::test
