#pragma once
// The moving-least-squares fit shared by the `mls` and `mmls` plugins (MLS: Lancaster and Salkauskas, Math.
// Comp. 1981; MMLS: Joldes, Chowdhury, Wittek, Doyle, Miller, Appl. Math. Comput. 2015).
//
// One evaluation at a point x:
//   w_I   quartic spline of r_I = |X_I - x| / R_I (zero for r_I >= 1),
//   p     polynomial basis in local scaled coordinates xi = (X - x) / s,
//   A     = sum_I w_I p(xi_I) p(xi_I)^T + mu D,   D = diag(0, 0, 0, 0, 1, ..., 1) (quadratic terms only),
//   N_I   = w_I p(0)^T A^{-1} p(xi_I),
// with mu = 0 for plain MLS and mu = m^2 sum_I w_I for the modified MLS of Joldes, Chowdhury, Wittek, Doyle and
// Miller (Appl. Math. Comput. 2015), which adds m^2 |a_q|^2 (weighted like the data) to the least-squares
// functional so that the quadratic coefficients a_q fall back to zero where the nodes cannot determine them.
#include <span>
#include <string>

#include "mtled/interfaces/shape_functions.hpp"
#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled::shapefunctions {

enum class PolynomialBasis { linear, quadratic };

// Number of basis terms in 3D: 4 (1, x, y, z) or 10 (plus the six quadratic monomials).
constexpr int basis_size(PolynomialBasis basis) { return basis == PolynomialBasis::linear ? 4 : 10; }

struct MovingLeastSquaresSettings {
  PolynomialBasis basis = PolynomialBasis::linear;
  // MMLS penalty m on the quadratic coefficients, dimensionless in the scaled coordinates; 0 = plain MLS.
  double quadratic_penalty = 0.0;
};

// Fills values (and gradients unless empty) for the nodes at `nodes` with support radii `radii`. Nodes whose
// support does not reach x contribute N = 0. On failure (no node reaches x, or the moment matrix is singular
// or too ill-conditioned) values and gradients are zero and ok is false. Thread-safe; allocates nothing.
// Throws std::invalid_argument when the span sizes disagree (a programming error, not user input).
ShapeFunctionFit evaluate_moving_least_squares(const MovingLeastSquaresSettings& settings, const Vec3& x,
                                               std::span<const Vec3> nodes, std::span<const double> radii,
                                               std::span<double> values, std::span<Vec3> gradients);

// value = sum_I N_I(x) node_values_I (and its gradient unless null) from the same fit, without forming each N_I.
// Thread-safe; ok = false (value and gradient zero) where evaluate_moving_least_squares fails.
ShapeFunctionFit interpolate_moving_least_squares(const MovingLeastSquaresSettings& settings, const Vec3& x,
                                                  std::span<const Vec3> nodes, std::span<const double> radii,
                                                  std::span<const Vec3> node_values, Vec3& value, Mat3* gradient);

// Below this estimate of 1/cond(A) the fit is refused: solves lose about cond(A) x machine epsilon, so this
// keeps the shape functions accurate to about 1e-6 relative (1e6 x 2.2e-16).
constexpr double kMinimumReciprocalCondition = 2.2e-10;

// `support_dilatation`, declared the same way by every shape function of this folder, read into Support.
struct Support {
  double dilatation = 0.0;
};
void declare_support_dilatation(ComponentDeclaration& declaration, double default_value, const std::string& advice);

}  // namespace mtled::shapefunctions
