// What is particular to `mls` and `mmls`: quadratic reproduction, the O(m^2) effect of the MMLS penalty,
// MMLS staying well posed where a quadratic fit is impossible, parameter validation, and the kernel's model
// built with each of them.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "mtled/discretisation.hpp"
#include "shape_function_fixtures.hpp"
#include "simd_targets.hpp"

namespace mtled::test {
namespace {

Discretisation::Options points_options(int points_per_tet) {
  Discretisation::Options options;
  options.integration_points_per_tet = points_per_tet;
  return options;
}

const Vec3 kBlock(0.03, 0.02, 0.025);  // as in the conformance suite: 5 mm cells, 30% jitter

// A random quadratic written around the evaluation point: q(X) = a + g.d + d^T H d, d = X - x, so that
// q(x) = a and grad q(x) = g exactly, with |g| s and |H| s^2 of order 1 over a support of radius s.
struct Quadratic {
  double a;
  Vec3 g;
  Mat3 H;
  double at(const Vec3& d) const { return a + g.dot(d) + d.dot(H * d); }
};
Quadratic random_quadratic(std::mt19937& random, double s) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Quadratic q;
  q.a = u(random);
  q.g = Vec3(u(random), u(random), u(random)) / s;
  Mat3 B;
  for (int i = 0; i < 9; ++i) B(i / 3, i % 3) = u(random);
  q.H = (B + B.transpose()) / (2.0 * s * s);
  return q;
}

struct ReproductionError {
  double value = 0.0;     // |sum N_I q_I - q(x)|, relative to |H| s^2
  double gradient = 0.0;  // |sum grad N_I q_I - grad q(x)| s, relative to |H| s^2
};
ReproductionError quadratic_error(const Evaluation& e, const Support& support, const Vec3& x, const Quadratic& q) {
  double value = 0.0;
  Vec3 gradient = Vec3::Zero();
  for (std::size_t i = 0; i < support.nodes.size(); ++i) {
    const double qi = q.at(support.nodes[i] - x);
    value += e.values[i] * qi;
    gradient += e.gradients[i] * qi;
  }
  const double s = support.mean_radius();
  const double curvature = q.H.norm() * s * s;
  return {std::abs(value - q.a) / curvature, (gradient - q.g).norm() * s / curvature};
}

// Worst quadratic-reproduction error over interior points of the jittered block.
ReproductionError worst_quadratic_error(const ShapeFunctions& shape_functions, int points, unsigned seed,
                                        std::size_t* fewest_nodes = nullptr) {
  const NodeCloud cloud = box_cloud(shape_functions.support_dilatation(), kBlock, 6, 4, 5, 0.3, 7);
  std::mt19937 random(seed);
  ReproductionError worst;
  for (int k = 0; k < points; ++k) {
    const Vec3 x = random_point(random, cloud.lower, cloud.upper, cloud.spacing);
    const Support support = support_at(cloud, x);
    const Evaluation e = evaluate(shape_functions, support, x);
    EXPECT_TRUE(e.fit.ok) << x.transpose();
    if (!e.fit.ok) continue;
    const ReproductionError error = quadratic_error(e, support, x, random_quadratic(random, support.mean_radius()));
    worst.value = std::max(worst.value, error.value);
    worst.gradient = std::max(worst.gradient, error.gradient);
    if (fewest_nodes != nullptr) *fewest_nodes = std::min(*fewest_nodes, support.nodes.size());
  }
  return worst;
}

TEST(MlsShapeFunctions, MinimumSupportSizeFollowsTheBasis) {
  EXPECT_EQ(make<ShapeFunctions>("mls", {{"basis", "linear"}})->minimum_support_size(), 4);
  EXPECT_EQ(make<ShapeFunctions>("mls", {{"basis", "quadratic"}})->minimum_support_size(), 10);
  EXPECT_EQ(make<ShapeFunctions>("mmls", json::object())->minimum_support_size(), 4);
  EXPECT_DOUBLE_EQ(make<ShapeFunctions>("mls", json::object())->support_dilatation(), 1.6);
}

// The linear basis' interpolate() sums its nodes in SIMD lanes (linear_node_sums.cpp): on every instruction set this
// CPU and the build support, it must be sum_I N_I v_I and sum_I v_I dN_I/dx^T from evaluate(), to their round-off.
// The supports reach 30% past the nodes' radii, so that lanes holding nodes of no weight are exercised, and their
// sizes vary, so that every remainder of a vector's width is.
TEST(MlsShapeFunctions, LinearInterpolationIsTheShapeFunctionSumsOnEverySimdTarget) {
  const auto mls = make<ShapeFunctions>("mls", {{"basis", "linear"}});
  const NodeCloud cloud = box_cloud(mls->support_dilatation(), kBlock, 6, 4, 5, 0.3, 3);
  for_each_simd_target([&](const std::string& target) {
    std::mt19937 random(5);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<std::size_t> sizes;
    for (int k = 0; k < 60; ++k) {
      const Vec3 x = random_point(random, cloud.lower, cloud.upper);
      const Support support = support_at(cloud, x, 0.3);
      std::vector<Vec3> field(support.nodes.size());
      for (Vec3& v : field) v = Vec3(unit(random), unit(random), unit(random));
      const Evaluation full = evaluate(*mls, support, x, true);
      Vec3 value;
      Mat3 gradient;
      ASSERT_EQ(mls->interpolate(x, support.nodes, support.radii, field, value, &gradient).ok, full.fit.ok);
      if (!full.fit.ok) continue;
      sizes.push_back(support.nodes.size());
      const auto [expected, expected_gradient] = field_sums(full, field);
      const double tolerance = roundoff_bound(full.fit, support.nodes.size());
      EXPECT_LE((value - expected).cwiseAbs().maxCoeff(), tolerance) << target << ", point " << k;
      EXPECT_LE((gradient - expected_gradient).cwiseAbs().maxCoeff(), tolerance / support.mean_radius())
          << target << ", point " << k;
    }
    std::sort(sizes.begin(), sizes.end());
    sizes.erase(std::unique(sizes.begin(), sizes.end()), sizes.end());
    EXPECT_GE(sizes.size(), 8U) << target << ": the supports should have many sizes";
  });
}

// Quadratic MLS reproduces quadratics exactly (to round-off); linear MLS does not, which shows the check bites.
TEST(MlsShapeFunctions, QuadraticBasisReproducesQuadraticFields) {
  const auto quadratic = make<ShapeFunctions>("mls", {{"basis", "quadratic"}, {"support_dilatation", 2.0}});
  const ReproductionError error = worst_quadratic_error(*quadratic, 200, 1);
  // Quadratic supports here have cond(A) up to ~1e6 (reciprocal ~1e-6): round-off ~1e6 x 50 nodes x 2e-16.
  EXPECT_LT(error.value, 1e-8);
  EXPECT_LT(error.gradient, 1e-8);
  RecordProperty("quadratic_mls_worst_value_error", fmt::format("{:.2e}", error.value));

  const auto linear = make<ShapeFunctions>("mls", {{"basis", "linear"}, {"support_dilatation", 2.0}});
  const ReproductionError linear_error = worst_quadratic_error(*linear, 50, 1);
  EXPECT_GT(linear_error.value, 1e-3);
  EXPECT_GT(linear_error.gradient, 1e-3);
}

// The MMLS penalty perturbs a well-posed quadratic fit by O(m^2): (A + mu D)^{-1} = A^{-1} - mu A^{-1} D A^{-1}
// + O(mu^2), mu = m^2 W. So the error ratio between m = 1e-3 and m = 1e-2 is 100 up to the O(mu) term
// (here mu / lambda_min(quadratic block) <~ 0.1, hence the 80..105 band), and the default penalty keeps the
// error small where the fit is well posed.
TEST(MmlsShapeFunctions, PenaltyChangesQuadraticReproductionByOrderPenaltySquared) {
  const json block = json::object();  // the default support_dilatation
  auto with_penalty = [&](double m) {
    json b = block;
    b["penalty"] = m;
    return worst_quadratic_error(*make<ShapeFunctions>("mmls", b), 100, 2);
  };
  const ReproductionError small = with_penalty(1e-3), large = with_penalty(1e-2);
  RecordProperty("mmls_error_m1e-3", fmt::format("{:.3e}", small.value));
  RecordProperty("mmls_error_m1e-2", fmt::format("{:.3e}", large.value));
  const double ratio = large.value / small.value;
  EXPECT_GT(ratio, 80.0);
  EXPECT_LT(ratio, 105.0);
  const double gradient_ratio = large.gradient / small.gradient;
  EXPECT_GT(gradient_ratio, 80.0);
  EXPECT_LT(gradient_ratio, 105.0);

  // With the default penalty: relative to the quadratic part |H| s^2 of the field.
  const ReproductionError by_default = worst_quadratic_error(*make<ShapeFunctions>("mmls", json::object()), 100, 2);
  EXPECT_LT(by_default.value, 2e-2);
  EXPECT_LT(by_default.gradient, 2e-2);
}

// With exactly 4 non-coplanar nodes the linear interpolant fits the data with zero residual and zero
// quadratic part, so it minimises the MMLS functional: MMLS must equal linear MLS, while quadratic MLS refuses.
TEST(MmlsShapeFunctions, FourNodesGiveTheLinearFit) {
  const auto mmls = make<ShapeFunctions>("mmls", json::object());
  const auto linear = make<ShapeFunctions>("mls", {{"basis", "linear"}});
  const auto quadratic = make<ShapeFunctions>("mls", {{"basis", "quadratic"}});
  std::mt19937 random(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Vertices of a regular tetrahedron around x, each moved by up to 30%: well shaped, so the comparison is
  // about the fit, not about the round-off of a nearly flat tet.
  const Vec3 corners[4] = {Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, 1, -1), Vec3(-1, -1, 1)};
  for (int k = 0; k < 50; ++k) {
    const Vec3 x(0.01, -0.02, 0.005);
    Support support;
    for (const Vec3& corner : corners) {
      support.nodes.push_back(x + 1e-3 * (corner + 0.3 * Vec3(u(random), u(random), u(random))));
      support.radii.push_back(3e-3);
    }
    const Evaluation a = evaluate(*mmls, support, x), b = evaluate(*linear, support, x);
    ASSERT_TRUE(a.fit.ok && b.fit.ok);
    EXPECT_FALSE(evaluate(*quadratic, support, x).fit.ok);
    const double tolerance = roundoff_bound(a.fit, 4) + roundoff_bound(b.fit, 4);
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(a.values[i], b.values[i], tolerance);
      EXPECT_LE((a.gradients[i] - b.gradients[i]).norm() * 3e-3, tolerance);
    }
  }
}

// Where the nodes cannot determine a quadratic (few nodes, or a thin slab such as a layer of surface nodes)
// plain quadratic MLS is singular or wildly conditioned; MMLS stays well posed, reproduces linear fields and
// keeps its shape functions of moderate size.
TEST(MmlsShapeFunctions, StaysWellPosedWhereQuadraticMlsCannot) {
  const auto mmls = make<ShapeFunctions>("mmls", json::object());
  const auto quadratic = make<ShapeFunctions>("mls", {{"basis", "quadratic"}});
  std::mt19937 random(12);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double R = 1e-2;
  const Vec3 x(0.3, 0.1, -0.2);
  struct Case {
    const char* what;
    int nodes;
    double thickness;  // of the slab holding the nodes, relative to R
  };
  for (const Case& c : {Case{"6 nodes", 6, 1.0}, Case{"9 nodes", 9, 1.0}, Case{"40 nodes in a 1% slab", 40, 0.01},
                        Case{"40 nodes in a 0.1% slab", 40, 0.001}}) {
    SCOPED_TRACE(c.what);
    Support support;
    for (int i = 0; i < c.nodes; ++i) {
      support.nodes.push_back(x + 0.6 * R * Vec3(u(random), u(random), c.thickness * u(random)));
      support.radii.push_back(R);
    }
    const Evaluation e = evaluate(*mmls, support, x);
    ASSERT_TRUE(e.fit.ok);
    const Evaluation q = evaluate(*quadratic, support, x);
    EXPECT_TRUE(!q.fit.ok || q.fit.reciprocal_condition < 1e-3 * e.fit.reciprocal_condition)
        << "quadratic MLS reciprocal condition " << q.fit.reciprocal_condition << ", MMLS "
        << e.fit.reciprocal_condition;
    double sum = 0.0, largest = 0.0;
    Mat3 gradient_moment = Mat3::Zero();
    for (std::size_t i = 0; i < support.nodes.size(); ++i) {
      sum += e.values[i];
      largest = std::max(largest, std::abs(e.values[i]));
      gradient_moment += e.gradients[i] * (support.nodes[i] - x).transpose();
    }
    const double tolerance = roundoff_bound(e.fit, support.nodes.size());
    EXPECT_NEAR(sum, 1.0, tolerance);
    EXPECT_LE((gradient_moment - Mat3::Identity()).norm(), tolerance);
    // Linear MLS on such supports gives |N_I| of order 1; a blown-up quadratic part would give far more.
    EXPECT_LT(largest, 3.0);
  }
}

// The conformance suite checks the gradients at the example's penalty; the penalty's own derivative terms
// (mu_k = m^2 (W_k + 4 W s_k / s)) grow with m, so check them at the ends of its range too, on a cloud whose
// support radii vary from node to node (so s_k is not zero).
TEST(MmlsShapeFunctions, GradientsAreExactAcrossThePenaltyRange) {
  for (double m : {1e-3, 0.1, 1.0}) {
    SCOPED_TRACE(m);
    const auto mmls = make<ShapeFunctions>("mmls", {{"penalty", m}});
    const NodeCloud cloud = box_cloud(mmls->support_dilatation(), kBlock, 6, 4, 5, 0.3, 19);
    check_gradients_by_central_differences(*mmls, cloud, 40, 4);
  }
}

// Out-of-range values are caught by the declaration, at the right JSON pointer, before anything is built.
TEST(ShapeFunctionParameters, BadValuesAreRejectedWithTheirLocation) {
  struct Case {
    const char* component;
    json block;
    const char* key;
  };
  const Case cases[] = {{"mls", {{"basis", "cubic"}}, "basis"},
                        {"mls", {{"support_dilatation", 0.5}}, "support_dilatation"},
                        {"mls", {{"support_dilatation", 12.0}}, "support_dilatation"},
                        {"mmls", {{"penalty", 0.0}}, "penalty"},
                        {"mmls", {{"penalty", -1e-2}}, "penalty"},
                        {"mmls", {{"penalty", 1e-6}}, "penalty"},
                        {"mmls", {{"basis", "linear"}}, "basis"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.block.dump());
    const ComponentDeclaration& declaration = catalog().load(Category::shape_function, c.component);
    std::vector<Problem> problems;
    validate_parameters(declaration, c.block, "/shape_function", problems);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_EQ(problems[0].where, std::string("/shape_function/") + c.key);
    EXPECT_FALSE(problems[0].message.empty());
  }
}

// A material that is never asked for stress here: the model only needs density and wave speed to set up.
class InertTestMaterial final : public Material {
 public:
  double density() const override { return 1000.0; }
  double p_wave_modulus() const override { return 1e5; }
  bool stress(const Mat3&, Mat3& S) const noexcept override {
    S.setZero();
    return true;
  }
  double energy(const Mat3&) const noexcept override { return 0.0; }
};

// The kernel's own supports (node-centred radii, strict |x - X_I| < R_I) on a jittered block with 1 and 4
// integration points per tet: every support must be accepted, and a homogeneous deformation u = G X must give
// F = I + G at every integration point and u(X_J) = G X_J at every node, to round-off.
TEST(ShapeFunctionsInTheModel, HomogeneousDeformationIsExactAtEveryIntegrationPoint) {
  struct Case {
    const char* component;
    json block;
    const char* label;
  };
  const Case cases[] = {{"mls", json::object(), "mls_linear"},
                        {"mls", {{"basis", "quadratic"}, {"support_dilatation", 2.0}}, "mls_quadratic"},
                        {"mmls", json::object(), "mmls"}};
  Mat3 G;
  G << 0.1, -0.02, 0.03, 0.01, -0.05, 0.02, -0.04, 0.015, 0.07;
  for (const Case& c : cases) {
    for (int points_per_tet : {1, 4}) {
      SCOPED_TRACE(c.component + c.block.dump() + " " + std::to_string(points_per_tet) + " points per tet");
      const auto shape_functions = make<ShapeFunctions>(c.component, c.block);
      Discretisation model(box_mesh(kBlock, 6, 4, 5, 0.3, 7), shape_functions, {std::make_shared<InertTestMaterial>()},
                           points_options(points_per_tet));
      const SupportStatistics stats = model.points().support;
      RecordProperty(fmt::format("{}_{}ip_support_min_mean_max", c.label, points_per_tet),
                     fmt::format("{}/{:.1f}/{}", stats.min, stats.mean, stats.max));
      RecordProperty(fmt::format("{}_{}ip_min_reciprocal_condition", c.label, points_per_tet),
                     fmt::format("{:.2e}", stats.min_reciprocal_condition));
      ASSERT_GT(stats.min_reciprocal_condition, 0.0);
      std::vector<double> u(3 * static_cast<std::size_t>(model.node_count()));
      for (Index i = 0; i < model.node_count(); ++i) {
        const Vec3 ui = G * model.nodes()[i];
        for (int d = 0; d < 3; ++d) u[3 * i + d] = ui[d];
      }
      const double tolerance =
          roundoff_bound(ShapeFunctionFit{true, stats.min_reciprocal_condition}, static_cast<std::size_t>(stats.max));
      double worst = 0.0;
      for (Index ip = 0; ip < model.points().count(); ++ip)
        worst = std::max(worst, (model.deformation_gradient(ip, u) - Mat3::Identity() - G).norm());
      EXPECT_LT(worst / G.norm(), tolerance);
      std::vector<double> interpolated(u.size());
      model.interpolate(u, interpolated);
      double worst_node = 0.0;
      for (std::size_t k = 0; k < u.size(); ++k) worst_node = std::max(worst_node, std::abs(interpolated[k] - u[k]));
      EXPECT_LT(worst_node / (G.norm() * kBlock.norm()), tolerance);
    }
  }
}

// A support too small for the basis is the user's choice of support_dilatation, so it must end as an input
// error that says what to change, not as a crash or NaN forces.
TEST(ShapeFunctionsInTheModel, SupportsTooSmallForTheBasisAreAnInputError) {
  const auto quadratic = make<ShapeFunctions>("mls", {{"basis", "quadratic"}, {"support_dilatation", 1.0}});
  try {
    Discretisation model(box_mesh(kBlock, 6, 4, 5, 0.3, 7), quadratic, {std::make_shared<InertTestMaterial>()},
                         points_options(1));
    FAIL() << "a quadratic basis with d_c = 1 cannot be well posed everywhere on this mesh";
  } catch (const InputError& e) {
    ASSERT_FALSE(e.problems().empty());
    EXPECT_EQ(e.problems()[0].where, "/shape_function");
    EXPECT_NE(e.problems()[0].message.find("support_dilatation"), std::string::npos) << e.problems()[0].message;
  }
}

}  // namespace
}  // namespace mtled::test
