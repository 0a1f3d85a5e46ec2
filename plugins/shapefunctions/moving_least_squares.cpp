#include "moving_least_squares.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "linear_node_sums.hpp"

namespace mtled::shapefunctions {

namespace {

template <int M>
using BasisVector = Eigen::Matrix<double, M, 1>;
template <int M>
using MomentMatrix = Eigen::Matrix<double, M, M>;

struct NodeWeight {
  double w = 0.0;
  Vec3 gradient = Vec3::Zero();  // dw/dx, with respect to the evaluation point
};

// Quartic spline w(r) = 1 - 6r^2 + 8r^3 - 3r^4 = (1 - r)^3 (1 + 3r) for r = |X_I - x| / R_I < 1 (the MTLED
// papers' weight, Horton et al. 2010),
// and dw/dx = w'(r) dr/dx = 12 (1 - r)^2 (X_I - x) / R_I^2, which needs no division by |X_I - x| and so stays
// smooth when x sits on the node. Radii that are not positive (or NaN) give no weight.
NodeWeight quartic_spline(const Vec3& offset, double radius) {
  NodeWeight result;
  if (!(radius > 0.0)) return result;
  const double r = offset.norm() / radius;
  if (!(r < 1.0)) return result;
  const double t = 1.0 - r;
  result.w = t * t * t * (1.0 + 3.0 * r);
  result.gradient = (12.0 * t * t / (radius * radius)) * offset;
  return result;
}

// p(xi) = [1, xi_1, xi_2, xi_3] or, quadratic, followed by [xi_1^2, xi_2^2, xi_3^2, r2 xi_1 xi_2, r2 xi_2 xi_3,
// r2 xi_3 xi_1] with r2 = sqrt(2). The sqrt(2) on the cross terms makes the sum of squared quadratic
// coefficients equal |Q|_F^2 for the quadratic form xi^T Q xi, so the MMLS penalty does not depend on how the
// axes are oriented (plain MLS is unaffected: the basis only changes by an invertible linear map).
template <int M>
BasisVector<M> basis_at(const Vec3& xi) {
  BasisVector<M> p;
  p[0] = 1.0;
  p[1] = xi[0];
  p[2] = xi[1];
  p[3] = xi[2];
  if constexpr (M == 10) {
    constexpr double kSqrt2 = 1.4142135623730951;
    p[4] = xi[0] * xi[0];
    p[5] = xi[1] * xi[1];
    p[6] = xi[2] * xi[2];
    p[7] = kSqrt2 * xi[0] * xi[1];
    p[8] = kSqrt2 * xi[1] * xi[2];
    p[9] = kSqrt2 * xi[2] * xi[0];
  }
  return p;
}

// The penalty acts on the quadratic terms only: D = diag(0, 0, 0, 0, 1, ..., 1).
template <int M>
BasisVector<M> quadratic_part(const BasisVector<M>& v) {
  BasisVector<M> result = v;
  result.template head<4>().setZero();
  return result;
}

// A node's weight and (only where the weight is not zero) its basis vector, computed once per point and kept for the
// passes that follow (one buffer per thread, reused from point to point).
template <int M>
struct NodeTerms {
  NodeWeight weight;
  BasisVector<M> p;
};

// What one point's fit needs besides the node terms: the local scale and the MMLS penalty, the factorised moment
// matrix, and c = A^{-1} p(0).
template <int M>
struct MomentFit {
  double inverse_scale = 0.0;
  double mu = 0.0;
  Vec3 mu_gradient = Vec3::Zero();
  Eigen::LDLT<MomentMatrix<M>> factor;
  BasisVector<M> c = BasisVector<M>::Zero();
  ShapeFunctionFit status;
};

// Factorises the moment matrix into fit.factor and, where it is positive definite and well enough conditioned, sets
// fit.c = A^{-1} p(0) and fit.status.ok.
template <int M>
void factorise(const MomentMatrix<M>& moment, MomentFit<M>& fit) {
  fit.factor.compute(moment);
  if (fit.factor.info() != Eigen::Success || !(fit.factor.vectorD().minCoeff() > 0.0)) return;
  const double reciprocal_condition = fit.factor.rcond();
  if (!std::isfinite(reciprocal_condition)) return;
  fit.status.reciprocal_condition = reciprocal_condition;
  if (reciprocal_condition < kMinimumReciprocalCondition) return;
  fit.c = fit.factor.solve(BasisVector<M>::Unit(0));
  fit.status.ok = true;
}

// The weights, the scale, the moment matrix and its factorisation at x (see evaluate_moving_least_squares); status.ok
// is false where no node reaches x or A is singular or too ill-conditioned.
template <int M>
MomentFit<M> fit_moments(double penalty, const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                         std::vector<NodeTerms<M>>& terms) {
  const std::size_t n = nodes.size();
  MomentFit<M> out;
  terms.resize(n);
  // The scale s is the weight-averaged support radius: close to the support size, so the scaled coordinates
  // of the nodes that count are O(1) and A is well scaled whatever the units and position; and smooth in x,
  // because entering and leaving nodes carry zero weight, so the MMLS penalty (which depends on s) is too.
  double total_weight = 0.0, weighted_radius = 0.0;
  Vec3 total_weight_gradient = Vec3::Zero(), weighted_radius_gradient = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const NodeWeight& weight = terms[i].weight = quartic_spline(nodes[i] - x, radii[i]);
    total_weight += weight.w;
    weighted_radius += weight.w * radii[i];
    total_weight_gradient += weight.gradient;
    weighted_radius_gradient += radii[i] * weight.gradient;
  }
  if (!(total_weight > 0.0) || !std::isfinite(weighted_radius)) return out;
  const double scale = weighted_radius / total_weight;
  out.inverse_scale = 1.0 / scale;
  const Vec3 scale_gradient = (weighted_radius_gradient - scale * total_weight_gradient) / total_weight;
  // Relative to the total weight, the penalty means the same for sparse and dense supports.
  const double m2 = penalty * penalty;
  out.mu = m2 * total_weight;
  out.mu_gradient = m2 * (total_weight_gradient + (4.0 * total_weight * out.inverse_scale) * scale_gradient);

  MomentMatrix<M> moment = MomentMatrix<M>::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    if (terms[i].weight.w == 0.0) continue;
    const Vec3 xi = out.inverse_scale * (nodes[i] - x);
    terms[i].p = basis_at<M>(xi);
    if constexpr (M == 4) {
      // The same products as below, from xi in registers: reading p back from memory just after writing it element by
      // element stalls (a load that straddles two stores cannot be forwarded), and this loop runs per node per point.
      const double w = terms[i].weight.w;
      const Vec3 w_xi = w * xi;
      moment(0, 0) += w;
      moment.template block<3, 1>(1, 0) += w_xi;
      moment.template block<3, 3>(1, 1).noalias() += w_xi * xi.transpose();
    } else {
      moment.noalias() += terms[i].weight.w * terms[i].p * terms[i].p.transpose();
    }
  }
  if constexpr (M == 4) moment.template block<1, 3>(0, 1) = moment.template block<3, 1>(1, 0).transpose();
  if constexpr (M > 4) moment.diagonal().template tail<M - 4>().array() += out.mu;

  factorise<M>(moment, out);
  return out;
}

// Derivatives. The shape functions do not depend on where the local basis is centred: for plain MLS any
// shift or scaling of a complete polynomial basis is an invertible linear map that cancels in
// p^T A^{-1} B, and the MMLS penalty acts on the quadratic coefficients, which a shift of the origin leaves
// unchanged. So we may differentiate with the origin frozen at x0 = x and the scale frozen at s0 = s(x0):
// then p(xi_I) is constant, dp(0)/dx_k = e_{1+k} / s0, and
//   A_k = sum_I w_I,k p_I p_I^T + mu_k D,   c = A^{-1} p(0),   gamma_k = A^{-1} (e_{1+k} / s0 - A_k c),
//   N_I,k = w_I gamma_k^T p_I + w_I,k c^T p_I.
// The scale does matter to MMLS (quadratic coefficients grow as s^2), so the penalty seen in the frozen frame
// is mu(x) = m^2 W(x) (s(x) / s0)^4, whose derivative at x0 is m^2 (W_k + 4 W s_k / s0).
//
// gamma's right-hand side e_{1+k} / s0 - A_k c, with A_k c = sum_I w_I,k p_I (p_I . c) + mu_k D c formed without A_k.
template <int M>
Eigen::Matrix<double, M, 3> gamma_right_hand_side(const MomentFit<M>& fit, const std::vector<NodeTerms<M>>& terms) {
  Eigen::Matrix<double, M, 3> rhs = Eigen::Matrix<double, M, 3>::Zero();
  rhs.template block<3, 3>(1, 0).diagonal().setConstant(fit.inverse_scale);
  for (const NodeTerms<M>& term : terms) {
    if (term.weight.w == 0.0) continue;
    rhs.noalias() -= (term.p.dot(fit.c) * term.p) * term.weight.gradient.transpose();
  }
  if constexpr (M > 4) rhs.noalias() -= quadratic_part<M>(fit.c) * fit.mu_gradient.transpose();
  return rhs;
}

template <int M>
ShapeFunctionFit fit(double penalty, const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                     std::span<double> values, std::span<Vec3> gradients) {
  thread_local std::vector<NodeTerms<M>> terms;
  const MomentFit<M> moments = fit_moments<M>(penalty, x, nodes, radii, terms);
  if (!moments.status.ok) return moments.status;
  const BasisVector<M>& c = moments.c;
  const bool with_gradients = !gradients.empty();
  Eigen::Matrix<double, M, 3> gamma = Eigen::Matrix<double, M, 3>::Zero();
  if (with_gradients) gamma = moments.factor.solve(gamma_right_hand_side<M>(moments, terms));

  bool finite = true;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const NodeWeight& weight = terms[i].weight;
    if (weight.w == 0.0) continue;
    const BasisVector<M>& p = terms[i].p;
    const double cp = c.dot(p);
    values[i] = weight.w * cp;
    finite = finite && std::isfinite(values[i]);
    if (with_gradients) {
      gradients[i] = weight.w * (gamma.transpose() * p) + cp * weight.gradient;
      finite = finite && gradients[i].allFinite();
    }
  }
  if (!finite) {  // cannot happen with a finite, accepted factorisation; never let NaN out regardless
    std::fill(values.begin(), values.end(), 0.0);
    std::fill(gradients.begin(), gradients.end(), Vec3::Zero());
    return {false, 0.0};
  }
  return moments.status;
}

// sum_I N_I v_I = (sum_I w_I v_I p_I^T) c and its gradient (sum_I w_I v_I p_I^T) gamma + sum_I (c . p_I) v_I w_I,k,
// without forming each N_I: the same fit, summed in the order of the terms.
template <int M>
ShapeFunctionFit interpolate(double penalty, const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                             std::span<const Vec3> node_values, Vec3& value, Mat3* gradient) {
  thread_local std::vector<NodeTerms<M>> terms;
  const MomentFit<M> moments = fit_moments<M>(penalty, x, nodes, radii, terms);
  if (!moments.status.ok) return moments.status;
  Eigen::Matrix<double, 3, M> weighted = Eigen::Matrix<double, 3, M>::Zero();  // sum_I w_I v_I p_I^T
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (terms[i].weight.w != 0.0) weighted.noalias() += (terms[i].weight.w * node_values[i]) * terms[i].p.transpose();
  value = weighted * moments.c;
  bool finite = value.allFinite();
  if (gradient != nullptr) {
    const Eigen::Matrix<double, M, 3> gamma = moments.factor.solve(gamma_right_hand_side<M>(moments, terms));
    Mat3 sum = weighted * gamma;
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if (terms[i].weight.w != 0.0)
        sum.noalias() += (moments.c.dot(terms[i].p) * node_values[i]) * terms[i].weight.gradient.transpose();
    *gradient = sum;
    finite = finite && sum.allFinite();
  }
  if (!finite) {  // as in fit(): never let NaN out
    value.setZero();
    if (gradient != nullptr) gradient->setZero();
    return {false, 0.0};
  }
  return moments.status;
}

// interpolate() for the linear basis, its node sums vectorised (linear_node_sums.hpp): the field on an image grid
// calls it millions of times. The sums are taken over the unscaled offsets d_I = X_I - x, since the scale is known
// only once the weights are summed, and scaled afterwards (p_I = [1, d_I / s]). The same fit, summed in another order.
ShapeFunctionFit interpolate_linear(const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                                    std::span<const Vec3> node_values, Vec3& value, Mat3* gradient) {
  thread_local NodeColumns columns;
  columns.resize(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    columns.dx[i] = nodes[i][0] - x[0];
    columns.dy[i] = nodes[i][1] - x[1];
    columns.dz[i] = nodes[i][2] - x[2];
    columns.radius[i] = radii[i];
    columns.vx[i] = node_values[i][0];
    columns.vy[i] = node_values[i][1];
    columns.vz[i] = node_values[i][2];
  }
  const LinearWeightSums sums = linear_weight_sums(columns);
  if (!(sums.weight > 0.0) || !std::isfinite(sums.weighted_radius)) return {};
  MomentFit<4> fit;
  const double inverse_scale = fit.inverse_scale = sums.weight / sums.weighted_radius;
  MomentMatrix<4> moment;
  moment(0, 0) = sums.weight;
  moment.block<3, 1>(1, 0) = inverse_scale * sums.first_moment;
  moment.block<1, 3>(0, 1) = moment.block<3, 1>(1, 0).transpose();
  moment.block<3, 3>(1, 1) = (inverse_scale * inverse_scale) * sums.second_moment;
  factorise<4>(moment, fit);
  if (!fit.status.ok) return fit.status;
  Eigen::Matrix<double, 3, 4> weighted;  // sum_I w_I v_I p_I^T
  weighted.col(0) = sums.weighted_value;
  weighted.rightCols<3>() = inverse_scale * sums.weighted_value_offset;
  value = weighted * fit.c;
  bool finite = value.allFinite();
  if (gradient != nullptr) {
    // gamma's right-hand side e_{1+k} / s - sum_I (c . p_I) p_I w_I,k^T, and sum_I (c . p_I) v_I w_I,k^T.
    const LinearGradientSums terms = linear_gradient_sums(columns, fit.c[0], inverse_scale * fit.c.tail<3>());
    Eigen::Matrix<double, 4, 3> rhs;
    rhs.row(0) = -terms.first.transpose();
    rhs.bottomRows<3>() = inverse_scale * (Mat3::Identity() - terms.offset_sum);
    *gradient = weighted * fit.factor.solve(rhs) + terms.value_sum;
    finite = finite && gradient->allFinite();
  }
  if (!finite) {  // as in fit(): never let NaN out
    value.setZero();
    if (gradient != nullptr) gradient->setZero();
    return {false, 0.0};
  }
  return fit.status;
}

}  // namespace

ShapeFunctionFit evaluate_moving_least_squares(const MovingLeastSquaresSettings& settings, const Vec3& x,
                                               std::span<const Vec3> nodes, std::span<const double> radii,
                                               std::span<double> values, std::span<Vec3> gradients) {
  if (radii.size() != nodes.size() || values.size() != nodes.size() ||
      (!gradients.empty() && gradients.size() != nodes.size()))
    throw std::invalid_argument("evaluate_moving_least_squares: nodes, radii, values and gradients differ in size");
  std::fill(values.begin(), values.end(), 0.0);
  std::fill(gradients.begin(), gradients.end(), Vec3::Zero());
  if (!x.allFinite()) return {};
  if (settings.basis == PolynomialBasis::linear) return fit<4>(0.0, x, nodes, radii, values, gradients);
  return fit<10>(settings.quadratic_penalty, x, nodes, radii, values, gradients);
}

ShapeFunctionFit interpolate_moving_least_squares(const MovingLeastSquaresSettings& settings, const Vec3& x,
                                                  std::span<const Vec3> nodes, std::span<const double> radii,
                                                  std::span<const Vec3> node_values, Vec3& value, Mat3* gradient) {
  if (radii.size() != nodes.size() || node_values.size() != nodes.size())
    throw std::invalid_argument("interpolate_moving_least_squares: nodes, radii and node values differ in size");
  value.setZero();
  if (gradient != nullptr) gradient->setZero();
  if (!x.allFinite()) return {};
  if (settings.basis == PolynomialBasis::linear)
    return interpolate_linear(x, nodes, radii, node_values, value, gradient);
  return interpolate<10>(settings.quadratic_penalty, x, nodes, radii, node_values, value, gradient);
}

void declare_support_dilatation(ComponentDeclaration& declaration, double default_value, const std::string& advice) {
  declaration.number("support_dilatation")
      .unit("1")
      .between(1.0, 5.0)
      .defaults(default_value)
      .doc(
          "d_c: each node's support radius is d_c times the mean length of the mesh edges at the node, and an "
          "integration point uses every node whose support covers it. Larger values give more nodes per "
          "support (smoother, better conditioned, slower). " +
          advice)
      .to<&Support::dilatation>();
}

}  // namespace mtled::shapefunctions
