#pragma once
// What the shape-function tests share: every shape function in the catalog (and every choice of its string
// parameters), irregular node clouds from jittered box meshes, supports and evaluations.
#include <memory>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "mtled/interfaces/shape_functions.hpp"
#include "test_support.hpp"

namespace mtled::test {

// One shape function to test: a catalog component with a parameter block.
struct ShapeFunctionVariant {
  std::string name;
  json parameters;
  std::string label;  // for test names: "mls", "mls_basis_quadratic"
};

// Each catalog component with its declaration's example, plus the example with each other choice of each of
// its string parameters (so mls is tested with both bases).
std::vector<ShapeFunctionVariant> shape_function_variants();

std::shared_ptr<ShapeFunctions> make_shape_functions(const ShapeFunctionVariant& variant);

// Nodes of a jittered box mesh with the kernel's support radii R_I = d_c x mean edge length at I.
struct NodeCloud {
  std::vector<Vec3> points;
  std::vector<double> radii;
  Vec3 lower = Vec3::Zero(), upper = Vec3::Zero();
  double spacing = 0.0;  // cell size
};
NodeCloud box_cloud(double dilatation, const Vec3& size, int nx, int ny, int nz, double jitter, unsigned seed);

// The nodes whose support covers x, |x - X_I| < R_I (1 + margin), as the kernel selects them.
struct Support {
  std::vector<Vec3> nodes;
  std::vector<double> radii;
  double mean_radius() const;
};
Support support_at(const NodeCloud& cloud, const Vec3& x, double margin = 0.0);

struct Evaluation {
  ShapeFunctionFit fit;
  std::vector<double> values;
  std::vector<Vec3> gradients;
};
Evaluation evaluate(const ShapeFunctions& shape_functions, const Support& support, const Vec3& x,
                    bool with_gradients = true);

// Uniform random point in the box [lower + inset, upper - inset].
Vec3 random_point(std::mt19937& random, const Vec3& lower, const Vec3& upper, double inset = 0.0);

// Round-off bound for sums of shape functions: solving with A costs about cond(A) x epsilon, summed over n
// nodes; capped at 1e-8 so that a component that reports a tiny reciprocal condition cannot loosen the
// checks into meaninglessness.
double roundoff_bound(const ShapeFunctionFit& fit, std::size_t n);

bool all_finite(const Evaluation& evaluation);

// sum_I N_I v_I and sum_I v_I dN_I/dx^T from an evaluation with gradients: what interpolate() must return.
struct FieldSums {
  Vec3 value = Vec3::Zero();
  Mat3 gradient = Mat3::Zero();
};
FieldSums field_sums(const Evaluation& evaluation, const std::vector<Vec3>& field);

// Compares the analytic gradients with central differences of the values at `points` random points of the
// cloud (two thirds at least one cell inside, where the fit must succeed; the rest anywhere). Adds a test
// failure for each disagreement; returns the worst |grad N - D(h)| x support radius.
double check_gradients_by_central_differences(const ShapeFunctions& shape_functions, const NodeCloud& cloud,
                                              int points, unsigned seed);

// Test names show the variant rather than its bytes.
void PrintTo(const ShapeFunctionVariant& variant, std::ostream* out);

}  // namespace mtled::test
