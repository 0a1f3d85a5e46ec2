#pragma once
// The sums over a point's nodes that the linear-basis MLS interpolation needs (interpolate_moving_least_squares),
// vectorised across the nodes with Google Highway and dispatched at run time to the best instruction set the CPU
// has. The field on an image grid evaluates this millions of times; node by node it was a chain of square roots
// and divisions that one lane at a time could not hide.
#include <cstddef>
#include <vector>

#include "mtled/types.hpp"

namespace mtled::shapefunctions {

// One point's nodes as columns: offsets d_I = X_I - x, support radii, nodal values, and (from linear_weight_sums)
// the weights' gradients dw_I/dx. Rows past `count` up to a multiple of kPadding have radius 0: no weight.
struct NodeColumns {
  static constexpr std::size_t kPadding = 8;  // the widest vector: 8 doubles (AVX-512)
  std::vector<double> dx, dy, dz, radius, vx, vy, vz, gx, gy, gz;
  std::size_t count = 0;

  // Room for n nodes, the padding rows zeroed.
  void resize(std::size_t n);
  std::size_t padded() const { return radius.size(); }
};

// sum_I w_I, sum_I w_I R_I and their gradients; sum_I w_I d_I, sum_I w_I d_I d_I^T, sum_I w_I v_I and
// sum_I w_I v_I d_I^T, with w the quartic spline of |d_I| / R_I. Fills the columns' gx, gy, gz with dw_I/dx.
struct LinearWeightSums {
  double weight = 0.0;
  double weighted_radius = 0.0;
  Vec3 weight_gradient = Vec3::Zero();
  Vec3 weighted_radius_gradient = Vec3::Zero();
  Vec3 first_moment = Vec3::Zero();
  Mat3 second_moment = Mat3::Zero();
  Vec3 weighted_value = Vec3::Zero();
  Mat3 weighted_value_offset = Mat3::Zero();
};
LinearWeightSums linear_weight_sums(NodeColumns& columns);

// With cp_I = c0 + c_offset . d_I: sum_I cp_I dw_I/dx, sum_I cp_I d_I (dw_I/dx)^T and sum_I cp_I v_I (dw_I/dx)^T.
struct LinearGradientSums {
  Vec3 first = Vec3::Zero();
  Mat3 offset_sum = Mat3::Zero();
  Mat3 value_sum = Mat3::Zero();
};
LinearGradientSums linear_gradient_sums(const NodeColumns& columns, double c0, const Vec3& c_offset);

}  // namespace mtled::shapefunctions
