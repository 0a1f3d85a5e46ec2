// Convergence: approximate a smooth field sampled at the nodes of jittered box meshes of three resolutions,
// u^h(x) = sum_I N_I(x) f(X_I), and measure the error of u^h and grad u^h at random points of the box. This is
// what the shape functions' accuracy means for MTLED: the displacement field is carried exactly so.
//
// Expected orders (MLS theory, e.g. Fries and Matthies 2004; Wendland, Scattered Data Approximation, ch. 4):
// a basis that reproduces polynomials of degree k gives errors O(h^{k+1}) for values and O(h^k) for first
// derivatives, with the support radius a fixed multiple of h. Every shape function reproduces linear fields
// (the conformance suite checks it): orders 2 and 1. One that reproduces quadratics exactly: 3 and 2. MMLS
// reproduces quadratics up to a bias of O(m^2) times the quadratic part, i.e. O(m^2 h^2): it behaves like a
// quadratic basis while that bias is below the O(h^3) error and tends to order 2 below; at these resolutions
// and m = 0.01 the two are comparable on the finest mesh, so its orders are expected between the two.
//
// Tolerance band: orders from three meshes whose jitter is drawn afresh at each resolution are not those of
// a self-similar refinement, and the coarsest mesh has k h ~ 0.8 rad per cell, still pre-asymptotic; so an
// observed order is accepted within 0.35 of the theoretical one (an error in a gradient or basis shows as an
// order off by one or more). Gradients of linear MLS converge faster than O(h) on these nearly regular
// clouds before the O(h) term (from the jitter's asymmetry) takes over (measured 1.5 then 1.3), so their
// upper limit is one order above the theoretical one.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include <fmt/format.h>

#include "shape_function_fixtures.hpp"

namespace mtled::test {
namespace {

constexpr double kSide = 0.04;                 // 40 mm cube
const Vec3 kWave = Vec3(1.1, -0.7, 0.9) * M_PI / kSide;  // about one wavelength across the cube
constexpr double kPhase = 0.4;
constexpr int kResolutions[3] = {6, 12, 24};   // cells per side
constexpr int kSamples = 1500;

double field(const Vec3& X) { return std::sin(kWave.dot(X) + kPhase); }
Vec3 field_gradient(const Vec3& X) { return std::cos(kWave.dot(X) + kPhase) * kWave; }

struct Errors {
  double value_rms = 0.0, value_max = 0.0;        // relative to max |f| = 1
  double gradient_rms = 0.0, gradient_max = 0.0;  // relative to max |grad f| = |k|
};

Errors approximation_errors(const ShapeFunctions& shape_functions, int cells) {
  const NodeCloud cloud = box_cloud(shape_functions.support_dilatation(), Vec3::Constant(kSide), cells, cells,
                                    cells, 0.25, 31);
  std::vector<double> nodal(cloud.points.size());
  for (std::size_t i = 0; i < nodal.size(); ++i) nodal[i] = field(cloud.points[i]);
  std::mt19937 random(2024);  // the same sample points at every resolution
  Errors errors;
  double value_sum = 0.0, gradient_sum = 0.0;
  for (int k = 0; k < kSamples; ++k) {
    const Vec3 x = random_point(random, cloud.lower, cloud.upper);
    std::vector<Index> ids;
    Support support;
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
      if ((cloud.points[i] - x).norm() < cloud.radii[i]) {
        ids.push_back(static_cast<Index>(i));
        support.nodes.push_back(cloud.points[i]);
        support.radii.push_back(cloud.radii[i]);
      }
    }
    const Evaluation e = evaluate(shape_functions, support, x);
    EXPECT_TRUE(e.fit.ok) << x.transpose();
    if (!e.fit.ok) continue;
    double u = 0.0;
    Vec3 grad = Vec3::Zero();
    for (std::size_t j = 0; j < ids.size(); ++j) {
      u += e.values[j] * nodal[ids[j]];
      grad += e.gradients[j] * nodal[ids[j]];
    }
    const double value_error = std::abs(u - field(x));
    const double gradient_error = (grad - field_gradient(x)).norm() / kWave.norm();
    value_sum += value_error * value_error;
    gradient_sum += gradient_error * gradient_error;
    errors.value_max = std::max(errors.value_max, value_error);
    errors.gradient_max = std::max(errors.gradient_max, gradient_error);
  }
  errors.value_rms = std::sqrt(value_sum / kSamples);
  errors.gradient_rms = std::sqrt(gradient_sum / kSamples);
  return errors;
}

// How well the shape functions reproduce a quadratic at a well-posed interior point, relative to the size of
// the quadratic over the support: round-off for a quadratic basis, O(m^2) for MMLS, O(1) for a linear basis.
double quadratic_reproduction_error(const ShapeFunctions& shape_functions) {
  const NodeCloud cloud = box_cloud(shape_functions.support_dilatation(), Vec3::Constant(kSide), 6, 6, 6, 0.25, 31);
  const Vec3 x = Vec3::Constant(0.5 * kSide) + Vec3(0.1, 0.2, -0.15) * cloud.spacing;
  const Support support = support_at(cloud, x);
  const Evaluation e = evaluate(shape_functions, support, x);
  EXPECT_TRUE(e.fit.ok);
  double value = 0.0;
  for (std::size_t i = 0; i < support.nodes.size(); ++i) {
    const Vec3 d = (support.nodes[i] - x) / support.mean_radius();
    value += e.values[i] * (d[0] * d[0] - 0.5 * d[1] * d[2] + 0.3 * d[2] * d[2]);  // zero at x
  }
  return std::abs(value);
}

class ShapeFunctionConvergence : public ::testing::TestWithParam<ShapeFunctionVariant> {};

TEST_P(ShapeFunctionConvergence, ErrorsFallAtTheOrderOfTheBasis) {
  const auto shape_functions = make_shape_functions(GetParam());
  Errors errors[3];
  for (int level = 0; level < 3; ++level) errors[level] = approximation_errors(*shape_functions, kResolutions[level]);
  // Linear basis (error O(1)), penalised quadratic (MMLS, O(m^2)) or exact quadratic (round-off).
  const double quadratic_error = quadratic_reproduction_error(*shape_functions);
  const bool exact_quadratic = quadratic_error < 1e-9;
  const bool penalised_quadratic = !exact_quadratic && quadratic_error < 5e-2;
  const double lowest_value_order = exact_quadratic ? 3.0 : 2.0;
  const double highest_value_order = exact_quadratic || penalised_quadratic ? 3.0 : 2.0;

  std::cout << fmt::format("{} {}: d_c = {}, quadratic reproduction error {:.2e}\n", GetParam().name,
                           GetParam().parameters.dump(), shape_functions->support_dilatation(), quadratic_error);
  std::cout << "  cells  h[mm]   value rms  value max   grad rms   grad max   order(value rms, grad rms)\n";
  for (int level = 0; level < 3; ++level) {
    std::string orders;
    if (level > 0) {
      const double ratio = static_cast<double>(kResolutions[level]) / kResolutions[level - 1];
      orders = fmt::format("{:.2f}, {:.2f}", std::log(errors[level - 1].value_rms / errors[level].value_rms) / std::log(ratio),
                           std::log(errors[level - 1].gradient_rms / errors[level].gradient_rms) / std::log(ratio));
    }
    std::cout << fmt::format("  {:5d} {:6.3f}  {:9.3e}  {:9.3e}  {:9.3e}  {:9.3e}  {}\n", kResolutions[level],
                             1e3 * kSide / kResolutions[level], errors[level].value_rms, errors[level].value_max,
                             errors[level].gradient_rms, errors[level].gradient_max, orders);
  }
  // The order over the two finer levels, the closest to asymptotic.
  const double ratio = static_cast<double>(kResolutions[2]) / kResolutions[1];
  const double value_order = std::log(errors[1].value_rms / errors[2].value_rms) / std::log(ratio);
  const double gradient_order = std::log(errors[1].gradient_rms / errors[2].gradient_rms) / std::log(ratio);
  RecordProperty("value_order", std::to_string(value_order));
  RecordProperty("gradient_order", std::to_string(gradient_order));
  RecordProperty("value_rms_finest", std::to_string(errors[2].value_rms));
  RecordProperty("gradient_rms_finest", std::to_string(errors[2].gradient_rms));
  constexpr double kBand = 0.35;
  EXPECT_GE(value_order, lowest_value_order - kBand);
  EXPECT_LE(value_order, highest_value_order + kBand);
  EXPECT_GE(gradient_order, lowest_value_order - 1.0 - kBand);
  EXPECT_LE(gradient_order, highest_value_order + kBand);
}

std::string variant_name(const ::testing::TestParamInfo<ShapeFunctionVariant>& info) { return info.param.label; }

INSTANTIATE_TEST_SUITE_P(Catalog, ShapeFunctionConvergence, ::testing::ValuesIn(shape_function_variants()),
                         variant_name);

}  // namespace
}  // namespace mtled::test
