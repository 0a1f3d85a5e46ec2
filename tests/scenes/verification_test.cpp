// Verification against problems with known answers, end to end through the mtled executable: the shipped
// uniaxial-compression scenes against the exact homogeneous solution, and the patch test on an irregular
// cloud for each shape function.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include <fmt/format.h>

#include "mtled/analysis/result_file.hpp"
#include "mtled/io/output.hpp"
#include "test_support.hpp"

namespace mtled::test {
namespace {

namespace fs = std::filesystem;
using Energy = std::function<double(const Vec3&)>;  // strain energy density of the principal stretches

// The paper's eq. (1): W = sum_i 2 mu / alpha^2 (lambda_bar_i^alpha - 1) + (J - 1)^2 / D,
// lambda_bar_i = J^(-1/3) lambda_i. Written here from the formula, independently of the plugins.
Energy ogden(double mu, double alpha, double D) {
  return [=](const Vec3& l) {
    const double J = l.prod(), s = std::cbrt(1.0 / J);
    double w = 0.0;
    for (int i = 0; i < 3; ++i) w += std::pow(s * l[i], alpha) - 1.0;
    return 2.0 * mu / (alpha * alpha) * w + (J - 1.0) * (J - 1.0) / D;
  };
}
// Neo-Hookean: W = mu/2 (J^(-2/3) I1 - 3) + (J - 1)^2 / D.
Energy neo_hookean(double mu, double D) {
  return [=](const Vec3& l) {
    const double J = l.prod();
    return 0.5 * mu * (std::pow(J, -2.0 / 3.0) * l.squaredNorm() - 3.0) + (J - 1.0) * (J - 1.0) / D;
  };
}

// dW/dlambda_i by central differences: truncation ~ h^2 W''' ~ 1e-12 relative, round-off ~ 1e-10.
double nominal_stress(const Energy& W, Vec3 l, int i) {
  const double h = 1e-6;
  Vec3 a = l, b = l;
  a[i] += h;
  b[i] -= h;
  return (W(a) - W(b)) / (2.0 * h);
}

// Homogeneous uniaxial state at axial stretch `stretch` with free sides: the lateral stretch makes the lateral
// nominal stress vanish (bisection to round-off); returns the axial nominal stress P_33 (Pa).
double exact_uniaxial_stress(const Energy& W, double stretch) {
  double lo = 0.8, hi = 1.5;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (nominal_stress(W, Vec3(mid, mid, stretch), 0) > 0.0 ? hi : lo) = mid;
  }
  return nominal_stress(W, Vec3(lo, lo, stretch), 2);
}

struct UniaxialCase {
  std::string scene;
  Energy energy;
  friend void PrintTo(const UniaxialCase& c, std::ostream* os) { *os << c.scene; }
};

class UniaxialCube : public ::testing::TestWithParam<UniaxialCase> {};

// Issue 3's acceptance: the nominal stress from the top face's reaction over the undeformed area is within 1%
// of the exact solution. With consistent integration (the default) a homogeneous deformation is reproduced
// exactly by the discrete equations, so what is left is the relaxation's stop at 1e-7 of the displacement:
// the tighter 1e-4 bound checks that, with a wide margin over it.
TEST_P(UniaxialCube, TopForceMatchesTheExactHomogeneousSolution) {
  const fs::path scene = source_dir() / "share/scenes" / GetParam().scene;
  const fs::path out = scratch_dir("uniaxial") / "out";
  const auto result = run_mtled({"run", scene.string(), "-o", out.string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;

  const json setup = read_json(scene);
  const json size = setup["mesh"]["size"];
  const double area = size[0].get<double>() * size[1].get<double>();
  const double stretch = 1.0 + setup["boundaries"][1]["displacement"][2].get<double>() / size[2].get<double>();
  const double exact = exact_uniaxial_stress(GetParam().energy, stretch);
  const json summary = read_json(out / "summary.json");
  const double computed = summary["final_reactions_N"]["top"][2].get<double>() / area;
  const double error = std::abs(computed / exact - 1.0);
  RecordProperty("nominal_stress_Pa", fmt::format("{:.3e}", computed));
  RecordProperty("exact_Pa", fmt::format("{:.3e}", exact));
  RecordProperty("relative_error", fmt::format("{:.3e}", error));
  EXPECT_LT(error, 0.01) << computed << " Pa against " << exact << " Pa";
  EXPECT_LT(error, 1e-4) << computed << " Pa against " << exact << " Pa";

  // The same force appears in reactions.csv's last row for the set (what users plot).
  const std::string csv = read_text(out / "reactions.csv");
  EXPECT_NE(csv.find("top"), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(ShippedScenes, UniaxialCube,
                         ::testing::Values(UniaxialCase{"uniaxial_cube_ogden.json", ogden(722.0, -1.3, 5.57738e-5)},
                                           UniaxialCase{"uniaxial_cube_neohookean.json",
                                                        neo_hookean(1000.0, 4.02684e-5)}));

// Patch test: every boundary node of an unstructured (Gmsh) cloud is given the affine displacement G X; the
// steady state inside must be that same field. The deformation is large (up to 8% strain, with shear), so
// this is the nonlinear patch test: a homogeneous F is an exact solution of the continuum problem for any
// hyperelastic law.
class PatchTest : public ::testing::TestWithParam<std::string> {};

TEST_P(PatchTest, AffineBoundaryDisplacementIsReproducedInside) {
  const double L = 0.01;
  const Mat3 G = (Mat3() << 0.05, 0.02, -0.01, 0.01, -0.03, 0.02, -0.02, 0.015, -0.08).finished();
  std::vector<double> gradient(G.data(), G.data() + 9);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) gradient[3 * r + c] = G(r, c);  // row by row
  const double tolerance = 1e-9;
  const json scene = {
      {"mesh", {{"type", "box"}, {"size", {L, L, L}}, {"target_nodes", 400}}},
      {"shape_function", {{"type", GetParam()}}},
      {"materials", {{{"type", "neo_hookean"}, {"mu", 1000}, {"D", 4.02684e-5}}}},
      {"boundaries",
       {{{"type", "prescribed_displacement"},
         {"name", "surface"},
         {"nodes", {{"box", {{"min", {-1, -1, -1}}, {"max", {1, 1, 1}}}}, {"surface_only", true}}},
         {"displacement", {0, 0, 0}},
         {"gradient", gradient}}}},
      {"integrator", {{"type", "dynamic_relaxation"}, {"load_steps", 200}, {"tolerance", tolerance}}}};
  const fs::path folder = scratch_dir("patch_" + GetParam());
  write_text(folder / "scene.json", scene.dump(2));
  const auto result = run_mtled({"run", (folder / "scene.json").string(), "-o", (folder / "out").string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;

  const ResultField field = read_result_vtu(folder / "out" / "result.vtu");
  double largest = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < field.points.size(); ++i) {
    const Vec3 exact = G * field.points[i];
    largest = std::max(largest, exact.norm());
    worst = std::max(worst, (field.displacement[i] - exact).norm());
  }
  RecordProperty("max_error_relative", fmt::format("{:.3e}", worst / largest));
  // The relaxation stops when its error estimate is below `tolerance` of the largest displacement; the
  // estimate is an extrapolation, so allow two orders of magnitude over it. Without consistent integration
  // the error on this 353-node cloud is 5.4% (MLS) and 15% (MMLS) (docs/validation.md), so the bound
  // discriminates.
  EXPECT_LT(worst / largest, 100 * tolerance) << worst << " m worst error on " << field.points.size() << " nodes";
}

INSTANTIATE_TEST_SUITE_P(EveryShapeFunction, PatchTest, ::testing::Values("mls", "mmls"));

}  // namespace
}  // namespace mtled::test
