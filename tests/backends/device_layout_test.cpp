// The cuda backend's host side, on every machine (no GPU needed): the sliced rows it sends to the device hold
// exactly the discretisation's rows, and the forces computed from them the way the kernels do (F per point from the
// point rows, the stress record, each node's sum over its row) are the force kernel's.
#include "device_layout.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "mtled/force_kernel.hpp"
#include "test_support.hpp"

namespace mtled {
namespace {

std::unique_ptr<test::Discretised> make_model(RowPrecision precision) {
  TetMesh mesh = test::box_mesh(Vec3(0.01, 0.012, 0.008), 5, 6, 4, 0.3, 3);
  const auto shape_functions = test::make<ShapeFunctions>("mmls", json::object());
  const auto material =
      test::make<Material>("ogden", {{"mu", 722.0}, {"alpha", -1.3}, {"D", 5.57738e-5}, {"density", 1000.0}});
  Discretisation::Options options;
  options.precision = precision;
  return std::make_unique<test::Discretised>(std::move(mesh), shape_functions,
                                             std::vector<std::shared_ptr<const Material>>{material}, options);
}

template <class Real>
void expect_rows_hold_the_model(const Discretisation& model) {
  const auto layout = cuda::build_device_layout<Real>(model);
  const GradientRows& gradients = model.gradients();
  // Each node's points in order, with its test gradient there, collected here point by point.
  std::vector<std::vector<std::pair<Index, Vec3>>> tests(static_cast<std::size_t>(model.node_count()));
  for (Index p = 0; p < model.points().count(); ++p)
    for (int k = 0; k < gradients.size(p); ++k) {
      const Index node = gradients.node(p, k);
      tests[static_cast<std::size_t>(node)].emplace_back(p, test_gradient(model, p, k));
    }
  const auto& points = layout.point_rows;
  ASSERT_EQ(points.slices(), (model.points().count() + cuda::kSlice - 1) / cuda::kSlice);
  EXPECT_EQ(points.entries, gradients.entries());
  for (Index p = 0; p < model.points().count(); ++p) {
    const std::int64_t slice = p / cuda::kSlice, lane = p % cuda::kSlice;
    const std::int64_t begin = points.slice_begin[slice], width = (points.slice_begin[slice + 1] - begin) / cuda::kSlice;
    ASSERT_EQ(points.row[static_cast<std::size_t>(p)], p);
    ASSERT_GE(width, gradients.size(p));
    for (std::int64_t k = 0; k < width; ++k) {
      const auto at = static_cast<std::size_t>(begin + k * cuda::kSlice + lane);
      if (k < gradients.size(p)) {
        ASSERT_EQ(points.column[at], gradients.node(p, static_cast<int>(k)));
        const Vec3 g = gradients.gradient(p, static_cast<int>(k));
        ASSERT_EQ(Vec3(points.gx[at], points.gy[at], points.gz[at]), g);  // the stored values, exactly
      } else {  // padding: the sink node, no gradient
        ASSERT_EQ(points.column[at], model.node_count());
        ASSERT_EQ(points.gx[at], Real(0));
      }
    }
  }
  // Every node in exactly one lane of the node rows, with its test gradients in point order.
  const auto& nodes = layout.node_rows;
  EXPECT_EQ(nodes.entries, gradients.entries());
  std::set<std::int32_t> seen;
  for (std::size_t i = 0; i < nodes.row.size(); ++i) {
    const std::int32_t node = nodes.row[i];
    if (node < 0) continue;
    ASSERT_TRUE(seen.insert(node).second) << "node " << node << " twice";
    const std::int64_t slice = static_cast<std::int64_t>(i) / cuda::kSlice, lane = static_cast<std::int64_t>(i) % cuda::kSlice;
    const std::int64_t begin = nodes.slice_begin[static_cast<std::size_t>(slice)];
    const std::int64_t width = (nodes.slice_begin[static_cast<std::size_t>(slice) + 1] - begin) / cuda::kSlice;
    const auto& expected = tests[static_cast<std::size_t>(node)];
    const auto length = static_cast<std::int64_t>(expected.size());
    ASSERT_GE(width, length);
    for (std::int64_t k = 0; k < width; ++k) {
      const auto at = static_cast<std::size_t>(begin + k * cuda::kSlice + lane);
      if (k < length) {
        const auto& [point, gradient] = expected[static_cast<std::size_t>(k)];
        ASSERT_EQ(nodes.column[at], point);
        for (int c = 0; c < 3; ++c)  // rounded once to the rows' precision
          ASSERT_EQ((c == 0 ? nodes.gx : c == 1 ? nodes.gy : nodes.gz)[at], static_cast<Real>(gradient[c]));
      } else {
        ASSERT_EQ(nodes.column[at], model.points().count());
      }
    }
  }
  EXPECT_EQ(static_cast<Index>(seen.size()), model.node_count());
  // Sorting within windows keeps the padding small: at most a quarter of the node rows' elements here.
  EXPECT_LE(static_cast<double>(nodes.elements()), 1.25 * static_cast<double>(nodes.entries));
}

TEST(CudaLayout, TheSlicedRowsHoldExactlyTheModelsRows) {
  expect_rows_hold_the_model<double>(make_model(RowPrecision::double_precision)->discretisation);
  expect_rows_hold_the_model<float>(make_model(RowPrecision::single_precision)->discretisation);
}

// The kernels' arithmetic on the host, over the sliced rows: the same forces as the host's force kernel to round-off
// (different summation orders only; bound as Discretisation.VectorisedForcesEqualTheOnePointDefinition...).
TEST(CudaLayout, ForcesFromTheSlicedRowsAreTheModelsForces) {
  const auto model = make_model(RowPrecision::double_precision);
  const auto layout = cuda::build_device_layout<double>(model->discretisation);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(-3e-4, 3e-4);
  const auto n = static_cast<std::size_t>(model->discretisation.node_count());
  std::vector<double> u(3 * n), expected(3 * n);
  for (double& v : u) v = uniform(random);
  ASSERT_EQ(model->kernel.internal_forces(u, expected), -1);

  std::vector<Mat3> records(static_cast<std::size_t>(model->discretisation.points().count()) + 1, Mat3::Zero());
  const auto& points = layout.point_rows;
  for (Index p = 0; p < model->discretisation.points().count(); ++p) {
    const std::int64_t slice = p / cuda::kSlice, lane = p % cuda::kSlice;
    Mat3 F = Mat3::Identity();
    for (std::int64_t e = points.slice_begin[slice] + lane; e < points.slice_begin[slice + 1]; e += cuda::kSlice) {
      const auto at = static_cast<std::size_t>(e), node = static_cast<std::size_t>(points.column[at]);
      const Vec3 un = node < n ? Vec3(u[3 * node], u[3 * node + 1], u[3 * node + 2]) : Vec3::Zero();
      F += un * Vec3(points.gx[at], points.gy[at], points.gz[at]).transpose();
    }
    Mat3 S;
    ASSERT_TRUE(model->discretisation.material(p).stress(F, S));
    records[static_cast<std::size_t>(p)] = model->discretisation.points().weights[p] * F * S;
  }
  std::vector<double> f(3 * n, 0.0);
  const auto& nodes = layout.node_rows;
  for (std::size_t i = 0; i < nodes.row.size(); ++i) {
    if (nodes.row[i] < 0) continue;
    const auto slice = i / cuda::kSlice, lane = i % cuda::kSlice;
    Vec3 sum = Vec3::Zero();
    for (std::int64_t e = nodes.slice_begin[slice] + static_cast<std::int64_t>(lane); e < nodes.slice_begin[slice + 1];
         e += cuda::kSlice) {
      const auto at = static_cast<std::size_t>(e);
      sum += records[static_cast<std::size_t>(nodes.column[at])] * Vec3(nodes.gx[at], nodes.gy[at], nodes.gz[at]);
    }
    for (int c = 0; c < 3; ++c) f[3 * static_cast<std::size_t>(nodes.row[i]) + static_cast<std::size_t>(c)] = sum[c];
  }
  double difference = 0.0, largest = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    difference = std::max(difference, std::abs(f[i] - expected[i]));
    largest = std::max(largest, std::abs(expected[i]));
  }
  EXPECT_GT(largest, 0.0);
  EXPECT_LE(difference, 1e-13 * largest);
}

}  // namespace
}  // namespace mtled
