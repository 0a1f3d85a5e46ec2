#include "shape_function_fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mtled::test {

std::vector<ShapeFunctionVariant> shape_function_variants() {
  std::vector<ShapeFunctionVariant> variants;
  for (const std::string& name : catalog().names(Category::shape_function)) {
    const ComponentDeclaration& declaration = catalog().load(Category::shape_function, name);
    const json example = declaration.example();
    variants.push_back({name, example, name});
    for (const ParameterSpec& spec : declaration.parameters()) {
      if (spec.type != ParameterType::string) continue;
      const json current = example.contains(spec.name) ? example[spec.name] : spec.default_value.value_or(json());
      for (const json& choice : spec.choices) {
        if (choice == current) continue;
        json block = example;
        block[spec.name] = choice;
        variants.push_back({name, block, name + "_" + spec.name + "_" + choice.get<std::string>()});
      }
    }
  }
  return variants;
}

std::shared_ptr<ShapeFunctions> make_shape_functions(const ShapeFunctionVariant& variant) {
  return make<ShapeFunctions>(variant.name, variant.parameters);
}

NodeCloud box_cloud(double dilatation, const Vec3& size, int nx, int ny, int nz, double jitter, unsigned seed) {
  const TetMesh mesh = box_mesh(size, nx, ny, nz, jitter, seed);
  NodeCloud cloud;
  cloud.points = mesh.points;
  cloud.radii = mean_edge_length_at_nodes(mesh);
  for (double& r : cloud.radii) r *= dilatation;
  cloud.lower = Vec3::Zero();
  cloud.upper = size;
  cloud.spacing = size.cwiseQuotient(Vec3(nx, ny, nz)).maxCoeff();
  return cloud;
}

double Support::mean_radius() const {
  double sum = 0.0;
  for (double r : radii) sum += r;
  return radii.empty() ? 0.0 : sum / static_cast<double>(radii.size());
}

Support support_at(const NodeCloud& cloud, const Vec3& x, double margin) {
  Support support;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if ((cloud.points[i] - x).norm() < cloud.radii[i] * (1.0 + margin)) {
      support.nodes.push_back(cloud.points[i]);
      support.radii.push_back(cloud.radii[i]);
    }
  }
  return support;
}

Evaluation evaluate(const ShapeFunctions& shape_functions, const Support& support, const Vec3& x,
                    bool with_gradients) {
  Evaluation e;
  // NaN-filled, so an implementation that leaves an entry unwritten is caught.
  e.values.assign(support.nodes.size(), std::numeric_limits<double>::quiet_NaN());
  e.gradients.assign(with_gradients ? support.nodes.size() : 0,
                     Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
  e.fit = shape_functions.evaluate(x, support.nodes, support.radii, e.values, e.gradients);
  return e;
}

Vec3 random_point(std::mt19937& random, const Vec3& lower, const Vec3& upper, double inset) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Vec3 x;
  for (int d = 0; d < 3; ++d) x[d] = lower[d] + inset + (upper[d] - lower[d] - 2.0 * inset) * unit(random);
  return x;
}

double roundoff_bound(const ShapeFunctionFit& fit, std::size_t n) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const double bound = 10.0 * static_cast<double>(n) * eps / std::max(fit.reciprocal_condition, 1e-300);
  return std::min(bound, 1e-8);
}

bool all_finite(const Evaluation& evaluation) {
  for (double v : evaluation.values)
    if (!std::isfinite(v)) return false;
  for (const Vec3& g : evaluation.gradients)
    if (!g.allFinite()) return false;
  return std::isfinite(evaluation.fit.reciprocal_condition);
}

FieldSums field_sums(const Evaluation& evaluation, const std::vector<Vec3>& field) {
  FieldSums sums;
  for (std::size_t i = 0; i < field.size(); ++i) {
    sums.value += evaluation.values[i] * field[i];
    sums.gradient += field[i] * evaluation.gradients[i].transpose();
  }
  return sums;
}

// D(h) = g + a h^2 + O(h^4) + round-off / h, so |D(2h) - D(h)| ~ 3 |a| h^2 estimates the truncation error
// of D(h) from the data; the analytic gradient must agree with D(h) within that estimate plus the round-off of
// the difference quotient. The expansion needs the values to be smooth over the stencil, so points where a
// node's support boundary (r = 1, where the weight is only C^2) crosses the stencil are skipped.
double check_gradients_by_central_differences(const ShapeFunctions& shape_functions, const NodeCloud& cloud,
                                              int points, unsigned seed) {
  std::mt19937 random(seed);
  double worst = 0.0;
  int checked = 0;
  for (int k = 0; k < 10 * points && checked < points; ++k) {
    const bool interior = k % 3 != 0;
    const Vec3 x = random_point(random, cloud.lower, cloud.upper, interior ? cloud.spacing : 0.0);
    // The same node list at x and x +- 2h: with the nodes just outside their supports (zero weight at x).
    const Support support = support_at(cloud, x, 0.01);
    const double s = support.mean_radius();
    const double h = 1e-3 * s;
    bool smooth = true;
    for (std::size_t i = 0; i < support.nodes.size(); ++i)
      smooth = smooth && std::abs((support.nodes[i] - x).norm() - support.radii[i]) > 3.0 * h;
    if (!smooth) continue;
    const Evaluation e = evaluate(shape_functions, support, x);
    EXPECT_TRUE(e.fit.ok || !interior) << "interior point " << x.transpose();
    if (!e.fit.ok) continue;
    ++checked;
    const double value_roundoff = roundoff_bound(e.fit, support.nodes.size());
    for (int d = 0; d < 3; ++d) {
      auto values_at = [&](double offset) {
        Vec3 y = x;
        y[d] += offset;
        const Evaluation shifted = evaluate(shape_functions, support, y, false);
        EXPECT_TRUE(shifted.fit.ok);
        return shifted.values;
      };
      const auto plus = values_at(h), minus = values_at(-h), plus2 = values_at(2 * h), minus2 = values_at(-2 * h);
      for (std::size_t i = 0; i < support.nodes.size(); ++i) {
        const double fd = (plus[i] - minus[i]) / (2 * h);
        const double fd2 = (plus2[i] - minus2[i]) / (4 * h);
        const double tolerance = std::abs(fd2 - fd) + 4.0 * value_roundoff / h + 1e-9 / s;
        EXPECT_NEAR(e.gradients[i][d], fd, tolerance) << "node " << i << ", direction " << d << " at " << x.transpose();
        worst = std::max(worst, std::abs(e.gradients[i][d] - fd) * s);
      }
    }
  }
  EXPECT_EQ(checked, points) << "too few points where the check applies";
  return worst;
}

void PrintTo(const ShapeFunctionVariant& variant, std::ostream* out) {
  *out << variant.name << " " << variant.parameters.dump();
}

}  // namespace mtled::test
