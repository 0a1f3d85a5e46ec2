#include "device_layout.hpp"

#include <algorithm>
#include <numeric>

namespace mtled::cuda {

namespace {

// Rows given as (length, entry(row, k) -> {column, gradient}), laid out slice by slice in `order`.
template <class Real, class Length, class Entry>
SlicedRows<Real> slice_rows(const std::vector<std::int32_t>& order, std::int32_t sink, Length length, Entry entry) {
  SlicedRows<Real> out;
  const auto rows = static_cast<std::int64_t>(order.size());
  const std::int64_t slices = (rows + kSlice - 1) / kSlice;
  out.slice_begin.assign(static_cast<std::size_t>(slices) + 1, 0);
  out.row.assign(static_cast<std::size_t>(slices * kSlice), -1);
  for (std::int64_t s = 0; s < slices; ++s) {
    std::int64_t width = 0;
    for (std::int64_t lane = 0; lane < kSlice && s * kSlice + lane < rows; ++lane)
      width = std::max<std::int64_t>(width, length(order[static_cast<std::size_t>(s * kSlice + lane)]));
    out.slice_begin[static_cast<std::size_t>(s) + 1] = out.slice_begin[static_cast<std::size_t>(s)] + width * kSlice;
  }
  const auto elements = static_cast<std::size_t>(out.elements());
  out.column.assign(elements, sink);
  out.gx.assign(elements, Real(0));
  out.gy.assign(elements, Real(0));
  out.gz.assign(elements, Real(0));
  std::int64_t entries = 0;
#pragma omp parallel for schedule(static) reduction(+ : entries)
  for (std::int64_t i = 0; i < rows; ++i) {
    const std::int32_t r = order[static_cast<std::size_t>(i)];
    const std::int64_t s = i / kSlice, lane = i % kSlice;
    out.row[static_cast<std::size_t>(i)] = r;
    const std::int64_t n = length(r);
    entries += n;
    for (std::int64_t k = 0; k < n; ++k) {
      const auto at = static_cast<std::size_t>(out.slice_begin[static_cast<std::size_t>(s)] + k * kSlice + lane);
      const auto [column, gradient] = entry(r, k);
      out.column[at] = column;
      out.gx[at] = static_cast<Real>(gradient[0]);
      out.gy[at] = static_cast<Real>(gradient[1]);
      out.gz[at] = static_cast<Real>(gradient[2]);
    }
  }
  out.entries = entries;
  return out;
}

}  // namespace

template <class Real>
DeviceLayout<Real> build_device_layout(const Discretisation& model) {
  DeviceLayout<Real> layout;
  layout.nodes = model.node_count();
  layout.points = model.points().count();
  const GradientRows& gradients = model.gradients();
  // Each node's integration points in point order (the supports transposed), and its test gradient at each,
  // t_pI = grad N_I + the consistent-integration correction of I at p.
  const SupportRows node_points = transpose_rows(layout.points, layout.nodes, [&](Index p, auto&& add) {
    for (int k = 0; k < gradients.size(p); ++k) add(gradients.node(p, k));
  });
  std::vector<Vec3> tests(node_points.nodes.size());
  {
    std::vector<std::int64_t> next(node_points.offsets.begin(), node_points.offsets.end() - 1);
    for (Index p = 0; p < layout.points; ++p)
      for (int k = 0; k < gradients.size(p); ++k) {
        const Index node = gradients.node(p, k);
        tests[static_cast<std::size_t>(next[static_cast<std::size_t>(node)]++)] = test_gradient(model, p, k);
      }
  }

  // Points in their own order: a warp's rows are 32 consecutive points, about equally long.
  std::vector<std::int32_t> point_order(static_cast<std::size_t>(layout.points));
  std::iota(point_order.begin(), point_order.end(), 0);
  layout.point_rows = slice_rows<Real>(
      point_order, layout.nodes, [&](std::int32_t p) { return gradients.size(p); },
      [&](std::int32_t p, std::int64_t k) {
        return std::pair{gradients.node(p, static_cast<int>(k)), gradients.gradient(p, static_cast<int>(k))};
      });

  // Nodes sorted by length, longest first, within windows of kSortWindow rows (a stable sort: ties keep node order).
  std::vector<std::int32_t> node_order(static_cast<std::size_t>(layout.nodes));
  std::iota(node_order.begin(), node_order.end(), 0);
  const auto length = [&](std::int32_t node) { return node_points.size(node); };
  for (std::size_t w = 0; w < node_order.size(); w += kSortWindow)
    std::stable_sort(node_order.begin() + static_cast<std::ptrdiff_t>(w),
                     node_order.begin() + static_cast<std::ptrdiff_t>(std::min(node_order.size(), w + kSortWindow)),
                     [&](std::int32_t a, std::int32_t b) { return length(a) > length(b); });
  layout.node_rows = slice_rows<Real>(node_order, layout.points, length, [&](std::int32_t node, std::int64_t k) {
    const std::int64_t e = node_points.offsets[static_cast<std::size_t>(node)] + k;
    return std::pair{node_points.nodes[static_cast<std::size_t>(e)], tests[static_cast<std::size_t>(e)]};
  });
  return layout;
}

template DeviceLayout<float> build_device_layout<float>(const Discretisation&);
template DeviceLayout<double> build_device_layout<double>(const Discretisation&);

}  // namespace mtled::cuda
