// Conformance suite: properties every shape function in the catalog must have, whatever its basis or weight.
// Each component is built through the real plugin loader from its declaration's example (and once for each
// other choice of its string parameters), and evaluated on irregular node clouds with the kernel's supports.
#include <gtest/gtest.h>
#include <omp.h>

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "shape_function_fixtures.hpp"

namespace mtled::test {
namespace {

// A soft-tissue sized block (30 x 20 x 25 mm, 5 mm cells) with interior nodes moved by up to 30% of a cell:
// irregular enough that no symmetry can hide an error, regular enough that every interior support is well posed.
const Vec3 kBlock(0.03, 0.02, 0.025);
constexpr int kCells[3] = {6, 4, 5};
constexpr double kJitter = 0.3;

class ShapeFunctionConformance : public ::testing::TestWithParam<ShapeFunctionVariant> {
 protected:
  void SetUp() override {
    shape_functions_ = make_shape_functions(GetParam());
    ASSERT_TRUE(shape_functions_);
    cloud_ = box_cloud(shape_functions_->support_dilatation(), kBlock, kCells[0], kCells[1], kCells[2], kJitter, 7);
  }
  // Points at least one cell inside the block: there every support is full, so every shape function must
  // succeed (near the surface a higher-order basis may legitimately refuse).
  Vec3 interior_point(std::mt19937& random) const {
    return random_point(random, cloud_.lower, cloud_.upper, cloud_.spacing);
  }

  std::shared_ptr<ShapeFunctions> shape_functions_;
  NodeCloud cloud_;
};

TEST(ShapeFunctionCatalog, HoldsTheMeshlessShapeFunctions) {
  const auto names = catalog().names(Category::shape_function);
  EXPECT_NE(std::find(names.begin(), names.end(), "mls"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "mmls"), names.end());
}

TEST_P(ShapeFunctionConformance, DeclarationIsDocumentedAndDefaultsAreValid) {
  const ComponentDeclaration& declaration = catalog().load(Category::shape_function, GetParam().name);
  EXPECT_FALSE(declaration.summary().empty());
  EXPECT_FALSE(declaration.example().contains("type")) << "examples are parameter blocks without \"type\"";
  for (const ParameterSpec& spec : declaration.parameters()) {
    SCOPED_TRACE(spec.name);
    EXPECT_FALSE(spec.doc.empty());
    const bool numeric = spec.type == ParameterType::number || spec.type == ParameterType::integer ||
                         spec.type == ParameterType::vector3 || spec.type == ParameterType::number_list;
    if (numeric) {
      EXPECT_FALSE(spec.unit.empty()) << "numeric parameters carry an SI unit (\"1\" if none)";
    }
    if (!spec.default_value) continue;
    if (spec.type == ParameterType::number || spec.type == ParameterType::integer) {
      EXPECT_TRUE(spec.range.contains(spec.default_value->get<double>())) << spec.range.describe();
    }
    if (!spec.choices.empty()) {
      EXPECT_NE(std::find(spec.choices.begin(), spec.choices.end(), *spec.default_value), spec.choices.end());
    }
  }
  // The kernel scales every support radius by support_dilatation(): it must be the declared parameter's value.
  if (declaration.find("support_dilatation") != nullptr) {
    const Parameters p = parameters(Category::shape_function, GetParam().name, GetParam().parameters);
    EXPECT_DOUBLE_EQ(shape_functions_->support_dilatation(), p.number("support_dilatation"));
  }
  EXPECT_GE(shape_functions_->support_dilatation(), 1.0);
  // Linear consistency in 3D needs at least 4 non-coplanar nodes.
  EXPECT_GE(shape_functions_->minimum_support_size(), 4);
}

// Sum N_I = 1, sum grad N_I = 0, sum N_I X_I = x, sum grad N_I X_I^T = I: what makes rigid motions and
// homogeneous strains exact (the patch test). Round-off bound from the moment matrix's condition.
TEST_P(ShapeFunctionConformance, PartitionOfUnityAndLinearReproduction) {
  std::mt19937 random(11);
  double worst_unity = 0.0, worst_linear = 0.0;
  for (int k = 0; k < 300; ++k) {
    // Two thirds interior (must succeed), one third anywhere, boundaries included (may refuse).
    const bool interior = k % 3 != 0;
    const Vec3 x = interior ? interior_point(random) : random_point(random, cloud_.lower, cloud_.upper);
    const Support support = support_at(cloud_, x);
    const Evaluation e = evaluate(*shape_functions_, support, x);
    ASSERT_TRUE(all_finite(e)) << "at " << x.transpose();
    if (interior) {
      ASSERT_TRUE(e.fit.ok) << "interior point " << x.transpose() << ", " << support.nodes.size() << " nodes";
    }
    if (!e.fit.ok) continue;
    ASSERT_GT(e.fit.reciprocal_condition, 0.0);
    ASSERT_LE(e.fit.reciprocal_condition, 1.0);
    const double s = support.mean_radius();
    const double tolerance = roundoff_bound(e.fit, support.nodes.size());
    double sum = 0.0;
    Vec3 sum_gradient = Vec3::Zero(), first_moment = Vec3::Zero();
    Mat3 gradient_moment = Mat3::Zero();
    for (std::size_t i = 0; i < support.nodes.size(); ++i) {
      sum += e.values[i];
      sum_gradient += e.gradients[i];
      // Offsets from x, so the check does not lose digits to the cloud's distance from the origin.
      first_moment += e.values[i] * (support.nodes[i] - x);
      gradient_moment += e.gradients[i] * (support.nodes[i] - x).transpose();
    }
    EXPECT_NEAR(sum, 1.0, tolerance) << x.transpose();
    EXPECT_LE(sum_gradient.norm() * s, tolerance) << x.transpose();
    EXPECT_LE(first_moment.norm() / s, tolerance) << x.transpose();
    // sum grad N_I (X_I - x)^T = sum grad N_I X_I^T - (sum grad N_I) x^T = I.
    EXPECT_LE((gradient_moment - Mat3::Identity()).norm(), tolerance) << x.transpose();
    worst_unity = std::max(worst_unity, std::abs(sum - 1.0));
    worst_linear = std::max(worst_linear, (gradient_moment - Mat3::Identity()).norm());
  }
  RecordProperty("worst_partition_of_unity_error", fmt::format("{:.3e}", worst_unity));
  RecordProperty("worst_linear_gradient_error", fmt::format("{:.3e}", worst_linear));
}

// Exact gradients against central differences of the values (see check_gradients_by_central_differences),
// at interior points and at points anywhere in the block (boundary supports are the lopsided ones).
TEST_P(ShapeFunctionConformance, GradientsMatchCentralDifferences) {
  const double worst = check_gradients_by_central_differences(*shape_functions_, cloud_, 60, 23);
  RecordProperty("worst_gradient_vs_fd_times_radius", fmt::format("{:.3e}", worst));
}

// The values-only call (the kernel's interpolation rows) must give the same values as the full call.
TEST_P(ShapeFunctionConformance, ValuesOnlyCallAgreesWithFullCall) {
  std::mt19937 random(5);
  for (int k = 0; k < 100; ++k) {
    const Vec3 x = random_point(random, cloud_.lower, cloud_.upper);
    const Support support = support_at(cloud_, x);
    const Evaluation full = evaluate(*shape_functions_, support, x, true);
    const Evaluation values_only = evaluate(*shape_functions_, support, x, false);
    ASSERT_EQ(full.fit.ok, values_only.fit.ok);
    ASSERT_TRUE(all_finite(values_only));
    if (!full.fit.ok) continue;
    const double tolerance = roundoff_bound(full.fit, support.nodes.size());
    for (std::size_t i = 0; i < support.nodes.size(); ++i) EXPECT_NEAR(values_only.values[i], full.values[i], tolerance);
  }
}

// interpolate() reads a nodal field at x: it must be sum_I N_I v_I and sum_I v_I dN_I/dx^T of the full call, to the
// round-off of those sums (each term is |N_I| |v_I|, with |v_I| <= 1 here), whether the component overrides it or
// not; and where the fit is refused it is refused too, with zeros.
TEST_P(ShapeFunctionConformance, InterpolateAgreesWithTheShapeFunctionSums) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int k = 0; k < 100; ++k) {
    const Vec3 x = random_point(random, cloud_.lower, cloud_.upper);
    const Support support = support_at(cloud_, x);
    std::vector<Vec3> field(support.nodes.size());
    for (Vec3& v : field) v = Vec3(unit(random), unit(random), unit(random));
    const Evaluation full = evaluate(*shape_functions_, support, x, true);
    Vec3 value = Vec3::Constant(7.0), value_only = Vec3::Constant(7.0);
    Mat3 gradient = Mat3::Constant(7.0);
    const ShapeFunctionFit fit =
        shape_functions_->interpolate(x, support.nodes, support.radii, field, value, &gradient);
    const ShapeFunctionFit fit_value_only =
        shape_functions_->interpolate(x, support.nodes, support.radii, field, value_only, nullptr);
    ASSERT_EQ(fit.ok, full.fit.ok);
    ASSERT_EQ(fit_value_only.ok, full.fit.ok);
    if (!full.fit.ok) {
      EXPECT_EQ(value, Vec3::Zero());
      EXPECT_EQ(gradient, Mat3::Zero());
      continue;
    }
    const auto [expected, expected_gradient] = field_sums(full, field);
    const double tolerance = roundoff_bound(full.fit, support.nodes.size());
    EXPECT_LE((value - expected).cwiseAbs().maxCoeff(), tolerance) << "at point " << k;
    EXPECT_LE((value_only - expected).cwiseAbs().maxCoeff(), tolerance) << "at point " << k;
    EXPECT_LE((gradient - expected_gradient).cwiseAbs().maxCoeff(), tolerance / support.mean_radius())
        << "at point " << k;
  }
}

// Moving, rotating or rescaling the whole cloud (and x) must not change the values; gradients rotate with the
// cloud and scale by 1/scale. This is what "local scaled coordinates" buys: the same answer in mm or m, near
// the origin or far from it. The supports are spherical, so rotations must not matter either. The tolerance
// adds the rounding of the moved coordinates themselves (epsilon |t| / s relative, amplified by cond(A)).
TEST_P(ShapeFunctionConformance, InvariantUnderTranslationRotationAndScaling) {
  struct Motion {
    double scale;
    Vec3 translation;  // in units of the block size
    double angle;
  };
  const Motion motions[] = {{1.0, Vec3(10.0, -7.0, 3.0), 0.0},
                            {1e-3, Vec3::Zero(), 0.0},
                            {2.5e3, Vec3(-0.5, 0.25, 2.0), 0.0},
                            {1.0, Vec3::Zero(), 1.1},
                            {37.0, Vec3(3.0, 1.0, -2.0), 2.3}};
  std::mt19937 random(99);
  for (const Motion& motion : motions) {
    const Mat3 Q = Eigen::AngleAxisd(motion.angle, Vec3(1.0, 2.0, -0.5).normalized()).toRotationMatrix();
    const Vec3 t = motion.scale * motion.translation.cwiseProduct(kBlock);
    auto move = [&](const Vec3& p) -> Vec3 { return motion.scale * (Q * p) + t; };
    for (int k = 0; k < 40; ++k) {
      const Vec3 x = interior_point(random);
      const Support support = support_at(cloud_, x);
      Support moved = support;
      for (auto& p : moved.nodes) p = move(p);
      for (auto& r : moved.radii) r *= motion.scale;
      const Evaluation a = evaluate(*shape_functions_, support, x);
      const Evaluation b = evaluate(*shape_functions_, moved, move(x));
      ASSERT_TRUE(a.fit.ok && b.fit.ok);
      const double s = support.mean_radius();
      const double tolerance = roundoff_bound(a.fit, support.nodes.size()) *
                               (1.0 + (motion.translation.cwiseProduct(kBlock).norm() + kBlock.norm()) / s);
      // The 1-norm condition estimate is not rotation invariant; under translation and scaling it must be.
      if (motion.angle == 0.0) {
        EXPECT_NEAR(b.fit.reciprocal_condition, a.fit.reciprocal_condition, 1e-6 * a.fit.reciprocal_condition);
      }
      for (std::size_t i = 0; i < support.nodes.size(); ++i) {
        EXPECT_NEAR(b.values[i], a.values[i], tolerance) << "scale " << motion.scale;
        const Vec3 expected = Q * a.gradients[i] / motion.scale;
        EXPECT_LE((b.gradients[i] - expected).norm() * motion.scale * s, tolerance) << "scale " << motion.scale;
      }
    }
  }
}

// Nodes outside their own support weigh nothing: they get N = 0 and leave the others unchanged.
TEST_P(ShapeFunctionConformance, NodesThatDoNotReachThePointGetZero) {
  std::mt19937 random(3);
  for (int k = 0; k < 20; ++k) {
    const Vec3 x = interior_point(random);
    const Support support = support_at(cloud_, x);
    Support padded = support;
    const double s = support.mean_radius();
    padded.nodes.insert(padded.nodes.begin(), x + Vec3(2.0 * s, 0.0, 0.0));  // radius s: does not reach x
    padded.radii.insert(padded.radii.begin(), s);
    padded.nodes.push_back(x + Vec3(0.0, 0.0, -s));  // exactly on its support boundary: w = 0
    padded.radii.push_back(s);
    const Evaluation a = evaluate(*shape_functions_, support, x);
    const Evaluation b = evaluate(*shape_functions_, padded, x);
    ASSERT_TRUE(a.fit.ok && b.fit.ok);
    EXPECT_EQ(b.values.front(), 0.0);
    EXPECT_EQ(b.values.back(), 0.0);
    EXPECT_EQ(b.gradients.front(), Vec3::Zero());
    EXPECT_EQ(b.gradients.back(), Vec3::Zero());
    const double tolerance = roundoff_bound(a.fit, support.nodes.size());
    for (std::size_t i = 0; i < support.nodes.size(); ++i) {
      EXPECT_NEAR(b.values[i + 1], a.values[i], tolerance);
      EXPECT_LE((b.gradients[i + 1] - a.gradients[i]).norm() * s, tolerance);
    }
  }
}

// Supports that cannot carry the basis: ok = false, every output finite (the kernel turns ok = false into an
// input error naming the point; a NaN would instead poison the whole run), no exception, no crash.
TEST_P(ShapeFunctionConformance, DegenerateSupportsAreRefusedCleanly) {
  const double R = 1e-2;  // support radius; the nodes below lie within R / 2 of x
  const Vec3 x(0.1, 0.2, 0.3);
  std::mt19937 random(17);
  std::uniform_real_distribution<double> unit(-0.5 * R, 0.5 * R);
  auto cloud = [&](int count, const Vec3& squash) {
    Support s;
    for (int i = 0; i < count; ++i) {
      s.nodes.push_back(x + Vec3(unit(random), unit(random), unit(random)).cwiseProduct(squash));
      s.radii.push_back(R);
    }
    return s;
  };
  struct Case {
    const char* what;
    Support support;
    Vec3 point;
  };
  std::vector<Case> cases;
  cases.push_back({"too few nodes for the basis", cloud(shape_functions_->minimum_support_size() - 1, Vec3::Ones()), x});
  cases.push_back({"coplanar nodes", cloud(40, Vec3(1.0, 1.0, 0.0)), x});
  cases.push_back({"coplanar nodes, point off their plane", cloud(40, Vec3(1.0, 1.0, 0.0)), x + Vec3(0, 0, 0.1 * R)});
  cases.push_back({"nearly coplanar nodes (1e-9 R thick)", cloud(40, Vec3(1.0, 1.0, 2e-9)), x});
  cases.push_back({"collinear nodes", cloud(40, Vec3(1.0, 0.0, 0.0)), x});
  cases.push_back({"all nodes at one place", cloud(40, Vec3::Zero()), x});
  cases.push_back({"no node reaches the point", cloud(40, Vec3::Ones()), x + Vec3(3.0 * R, 0, 0)});
  cases.push_back({"no nodes", Support{}, x});
  Support zero_radii = cloud(40, Vec3::Ones());
  std::fill(zero_radii.radii.begin(), zero_radii.radii.end(), 0.0);
  cases.push_back({"zero support radii", zero_radii, x});
  cases.push_back({"point not finite", cloud(40, Vec3::Ones()), Vec3(std::nan(""), 0.0, 0.0)});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    for (bool gradients : {true, false}) {
      Evaluation e;
      ASSERT_NO_THROW(e = evaluate(*shape_functions_, c.support, c.point, gradients));
      EXPECT_FALSE(e.fit.ok);
      EXPECT_TRUE(all_finite(e));
      EXPECT_GE(e.fit.reciprocal_condition, 0.0);
    }
  }
  // The same cloud with enough well-spread nodes is fine: the refusals above are about the geometry.
  const Support good = cloud(60, Vec3::Ones());
  EXPECT_TRUE(evaluate(*shape_functions_, good, x).fit.ok);
}

// Called from OpenMP threads by the kernel: concurrent evaluations must give exactly the serial results.
TEST_P(ShapeFunctionConformance, ConcurrentEvaluationMatchesSerial) {
  std::mt19937 random(41);
  std::vector<Vec3> points(400);
  for (auto& p : points) p = random_point(random, cloud_.lower, cloud_.upper);
  std::vector<Support> supports;
  for (const auto& p : points) supports.push_back(support_at(cloud_, p));
  std::vector<Evaluation> serial(points.size()), parallel(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) serial[k] = evaluate(*shape_functions_, supports[k], points[k]);
  const auto n = static_cast<long>(points.size());
#pragma omp parallel for num_threads(4) schedule(dynamic, 7)
  for (long k = 0; k < n; ++k) parallel[k] = evaluate(*shape_functions_, supports[k], points[k]);
  for (std::size_t k = 0; k < points.size(); ++k) {
    ASSERT_EQ(serial[k].fit.ok, parallel[k].fit.ok);
    for (std::size_t i = 0; i < serial[k].values.size(); ++i) {
      ASSERT_EQ(serial[k].values[i], parallel[k].values[i]);
      ASSERT_EQ(serial[k].gradients[i], parallel[k].gradients[i]);
    }
  }
}

std::string variant_name(const ::testing::TestParamInfo<ShapeFunctionVariant>& info) { return info.param.label; }

INSTANTIATE_TEST_SUITE_P(Catalog, ShapeFunctionConformance, ::testing::ValuesIn(shape_function_variants()),
                         variant_name);

}  // namespace
}  // namespace mtled::test
