// Compiled once per instruction set Highway targets (hwy/foreach_target.h re-includes this file).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "linear_node_sums.cpp"
#include "linear_node_sums.hpp"

#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <array>

HWY_BEFORE_NAMESPACE();
namespace mtled::shapefunctions::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using Tag = hn::ScalableTag<double>;
using V = hn::Vec<Tag>;

double total(V v) { return hn::GetLane(hn::SumOfLanes(Tag(), v)); }

void LinearWeightSumsImpl(NodeColumns& columns, LinearWeightSums& out) {
  const Tag d;
  const V zero = hn::Zero(d), one = hn::Set(d, 1.0), three = hn::Set(d, 3.0), twelve = hn::Set(d, 12.0);
  V weight = zero, weighted_radius = zero;
  std::array<V, 3> weight_gradient{zero, zero, zero}, weighted_radius_gradient{zero, zero, zero};
  std::array<V, 3> first{zero, zero, zero}, value{zero, zero, zero};
  std::array<V, 6> second{zero, zero, zero, zero, zero, zero};  // xx, xy, xz, yy, yz, zz
  std::array<V, 9> value_offset{};                              // row-major: v_a (w d_b)
  value_offset.fill(zero);
  for (std::size_t i = 0; i < columns.padded(); i += hn::Lanes(d)) {
    const std::array<V, 3> offset{hn::LoadU(d, columns.dx.data() + i), hn::LoadU(d, columns.dy.data() + i),
                                  hn::LoadU(d, columns.dz.data() + i)};
    const V radius = hn::LoadU(d, columns.radius.data() + i);
    const V distance2 =
        hn::MulAdd(offset[0], offset[0], hn::MulAdd(offset[1], offset[1], hn::Mul(offset[2], offset[2])));
    const V r = hn::Div(hn::Sqrt(distance2), radius);
    // Quartic spline w = (1 - r)^3 (1 + 3r) and dw/dx = 12 (1 - r)^2 d / R^2 where 0 <= r < 1 and R > 0 (the
    // padding's 0 / 0 is NaN, which compares false); zero elsewhere.
    const auto reached = hn::And(hn::Lt(r, one), hn::Gt(radius, zero));
    const V t = hn::Sub(one, r);
    const V t2 = hn::Mul(t, t);
    const V w = hn::IfThenElseZero(reached, hn::Mul(hn::Mul(t2, t), hn::MulAdd(three, r, one)));
    const V slope = hn::IfThenElseZero(reached, hn::Div(hn::Mul(twelve, t2), hn::Mul(radius, radius)));
    const std::array<V, 3> g{hn::Mul(slope, offset[0]), hn::Mul(slope, offset[1]), hn::Mul(slope, offset[2])};
    hn::StoreU(g[0], d, columns.gx.data() + i);
    hn::StoreU(g[1], d, columns.gy.data() + i);
    hn::StoreU(g[2], d, columns.gz.data() + i);
    const std::array<V, 3> v{hn::LoadU(d, columns.vx.data() + i), hn::LoadU(d, columns.vy.data() + i),
                             hn::LoadU(d, columns.vz.data() + i)};
    weight = hn::Add(weight, w);
    weighted_radius = hn::MulAdd(w, radius, weighted_radius);
    const std::array<V, 3> w_offset{hn::Mul(w, offset[0]), hn::Mul(w, offset[1]), hn::Mul(w, offset[2])};
    for (int a = 0; a < 3; ++a) {
      weight_gradient[a] = hn::Add(weight_gradient[a], g[a]);
      weighted_radius_gradient[a] = hn::MulAdd(radius, g[a], weighted_radius_gradient[a]);
      first[a] = hn::Add(first[a], w_offset[a]);
      value[a] = hn::MulAdd(w, v[a], value[a]);
      for (int b = 0; b < 3; ++b) value_offset[3 * a + b] = hn::MulAdd(v[a], w_offset[b], value_offset[3 * a + b]);
    }
    second[0] = hn::MulAdd(w_offset[0], offset[0], second[0]);
    second[1] = hn::MulAdd(w_offset[0], offset[1], second[1]);
    second[2] = hn::MulAdd(w_offset[0], offset[2], second[2]);
    second[3] = hn::MulAdd(w_offset[1], offset[1], second[3]);
    second[4] = hn::MulAdd(w_offset[1], offset[2], second[4]);
    second[5] = hn::MulAdd(w_offset[2], offset[2], second[5]);
  }
  out.weight = total(weight);
  out.weighted_radius = total(weighted_radius);
  for (int a = 0; a < 3; ++a) {
    out.weight_gradient[a] = total(weight_gradient[a]);
    out.weighted_radius_gradient[a] = total(weighted_radius_gradient[a]);
    out.first_moment[a] = total(first[a]);
    out.weighted_value[a] = total(value[a]);
    for (int b = 0; b < 3; ++b) out.weighted_value_offset(a, b) = total(value_offset[3 * a + b]);
  }
  constexpr int kRow[6] = {0, 0, 0, 1, 1, 2}, kColumn[6] = {0, 1, 2, 1, 2, 2};
  for (int e = 0; e < 6; ++e)
    out.second_moment(kRow[e], kColumn[e]) = out.second_moment(kColumn[e], kRow[e]) = total(second[e]);
}

void LinearGradientSumsImpl(const NodeColumns& columns, double c0, const Vec3& c_offset, LinearGradientSums& out) {
  const Tag d;
  const V zero = hn::Zero(d), constant = hn::Set(d, c0);
  const std::array<V, 3> c{hn::Set(d, c_offset[0]), hn::Set(d, c_offset[1]), hn::Set(d, c_offset[2])};
  std::array<V, 3> first{zero, zero, zero};
  std::array<V, 9> offset_sum{}, value_sum{};  // row-major: d_a (cp g_b), v_a (cp g_b)
  offset_sum.fill(zero);
  value_sum.fill(zero);
  for (std::size_t i = 0; i < columns.padded(); i += hn::Lanes(d)) {
    const std::array<V, 3> offset{hn::LoadU(d, columns.dx.data() + i), hn::LoadU(d, columns.dy.data() + i),
                                  hn::LoadU(d, columns.dz.data() + i)};
    const std::array<V, 3> v{hn::LoadU(d, columns.vx.data() + i), hn::LoadU(d, columns.vy.data() + i),
                             hn::LoadU(d, columns.vz.data() + i)};
    const V cp = hn::MulAdd(c[0], offset[0], hn::MulAdd(c[1], offset[1], hn::MulAdd(c[2], offset[2], constant)));
    const std::array<V, 3> cp_g{hn::Mul(cp, hn::LoadU(d, columns.gx.data() + i)),
                                hn::Mul(cp, hn::LoadU(d, columns.gy.data() + i)),
                                hn::Mul(cp, hn::LoadU(d, columns.gz.data() + i))};
    for (int a = 0; a < 3; ++a) {
      first[a] = hn::Add(first[a], cp_g[a]);
      for (int b = 0; b < 3; ++b) {
        offset_sum[3 * a + b] = hn::MulAdd(offset[a], cp_g[b], offset_sum[3 * a + b]);
        value_sum[3 * a + b] = hn::MulAdd(v[a], cp_g[b], value_sum[3 * a + b]);
      }
    }
  }
  for (int a = 0; a < 3; ++a) {
    out.first[a] = total(first[a]);
    for (int b = 0; b < 3; ++b) {
      out.offset_sum(a, b) = total(offset_sum[3 * a + b]);
      out.value_sum(a, b) = total(value_sum[3 * a + b]);
    }
  }
}

}  // namespace mtled::shapefunctions::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtled::shapefunctions {

HWY_EXPORT(LinearWeightSumsImpl);
HWY_EXPORT(LinearGradientSumsImpl);

void NodeColumns::resize(std::size_t n) {
  count = n;
  const std::size_t padded_count = (n + kPadding - 1) / kPadding * kPadding;
  for (std::vector<double>* column : {&dx, &dy, &dz, &radius, &vx, &vy, &vz, &gx, &gy, &gz}) {
    column->resize(padded_count);
    std::fill(column->begin() + static_cast<std::ptrdiff_t>(n), column->end(), 0.0);
  }
}

LinearWeightSums linear_weight_sums(NodeColumns& columns) {
  LinearWeightSums out;
  HWY_DYNAMIC_DISPATCH(LinearWeightSumsImpl)(columns, out);
  return out;
}

LinearGradientSums linear_gradient_sums(const NodeColumns& columns, double c0, const Vec3& c_offset) {
  LinearGradientSums out;
  HWY_DYNAMIC_DISPATCH(LinearGradientSumsImpl)(columns, c0, c_offset, out);
  return out;
}

}  // namespace mtled::shapefunctions
#endif  // HWY_ONCE
