#pragma once
#include <span>

#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled {

struct ShapeFunctionFit {
  bool ok = false;
  double reciprocal_condition = 0.0;  // of the moment matrix in local scaled coordinates
};

// Meshless shape functions (MLS, MMLS, ...). The kernel finds, for each evaluation point x, the nodes I whose
// support radius R_I covers x (|x - X_I| < R_I, R_I = support_dilatation() x mean edge length at I) and asks
// for the shape-function values and reference gradients there. Implementations must be thread-safe.
class ShapeFunctions {
 public:
  static constexpr Category category = Category::shape_function;
  virtual ~ShapeFunctions();

  virtual double support_dilatation() const = 0;
  // Fewest support nodes for which the fit can be well posed (4 for a linear basis in 3D).
  virtual int minimum_support_size() const = 0;
  // Fills values[i] = N_i(x) and, unless `gradients` is empty, gradients[i] = dN_i/dX(x), for the nodes
  // at `nodes` with support radii `radii`. Returns ok = false when the moment matrix is singular.
  virtual ShapeFunctionFit evaluate(const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                                    std::span<double> values, std::span<Vec3> gradients) const = 0;
  // value = sum_i N_i(x) node_values[i] and, unless `gradient` is null, its gradient (rows: components): a field
  // the nodes carry, read at x (how a run is carried onto other points or an image grid). The default sums
  // evaluate()'s values; a provider may override it to skip forming each N_i.
  virtual ShapeFunctionFit interpolate(const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                                       std::span<const Vec3> node_values, Vec3& value, Mat3* gradient) const;
};

}  // namespace mtled
