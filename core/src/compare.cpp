#include "mtled/compare.hpp"

#include <fmt/format.h>

#include <cmath>

#include "mtled/output.hpp"
#include "mtled/point_search.hpp"

namespace fs = std::filesystem;

namespace mtled {

namespace {
fs::path result_file(const fs::path& run) { return fs::is_directory(run) ? run / "result.vtu" : run; }
}  // namespace

std::vector<Vec3> interpolate_displacements(const std::vector<Vec3>& nodes, const std::vector<Vec3>& displacement,
                                            const std::vector<Vec3>& points, PluginCatalog& catalog) {
  const ComponentDeclaration& declaration = catalog.load(Category::shape_function, "mls", "mtled compare");
  std::vector<Problem> problems;
  const Parameters parameters = validate_parameters(declaration, json::object(), "", problems);
  const auto mls = catalog.create<ShapeFunctions>("mls", parameters);

  const PointSearch search(nodes);
  constexpr std::size_t kNeighbours = 10;
  std::vector<double> radius(nodes.size());
  std::vector<Index> nearest;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    search.nearest(nodes[i], kNeighbours + 1, nearest);  // the node itself comes first
    radius[i] = 1.3 * (nodes[static_cast<std::size_t>(nearest.back())] - nodes[i]).norm();
  }
  const double max_radius = *std::max_element(radius.begin(), radius.end());

  std::vector<Vec3> out(points.size(), Vec3::Zero());
  std::vector<Index> candidates, support;
  std::vector<Vec3> coordinates;
  std::vector<double> radii, values;
  for (std::size_t p = 0; p < points.size(); ++p) {
    search.within(points[p], max_radius, candidates);
    support.clear();
    for (Index i : candidates)
      if ((nodes[static_cast<std::size_t>(i)] - points[p]).norm() < radius[static_cast<std::size_t>(i)]) support.push_back(i);
    if (static_cast<int>(support.size()) < mls->minimum_support_size()) {
      // Outside A's cloud (a coarser boundary): fall back to the nearest nodes.
      search.nearest(points[p], 2 * kNeighbours, support);
    }
    coordinates.clear();
    radii.clear();
    for (Index i : support) {
      coordinates.push_back(nodes[static_cast<std::size_t>(i)]);
      radii.push_back(std::max(radius[static_cast<std::size_t>(i)],
                               1.01 * (nodes[static_cast<std::size_t>(i)] - points[p]).norm()));
    }
    values.resize(support.size());
    if (!mls->evaluate(points[p], coordinates, radii, values, {}).ok)
      throw std::runtime_error(fmt::format("cannot interpolate at ({:g}, {:g}, {:g}): degenerate neighbourhood",
                                           points[p][0], points[p][1], points[p][2]));
    for (std::size_t k = 0; k < support.size(); ++k) out[p] += values[k] * displacement[static_cast<std::size_t>(support[k])];
  }
  return out;
}

Comparison compare_runs(const fs::path& a, const fs::path& b, PluginCatalog& catalog) {
  const ResultField field_a = read_result_vtu(result_file(a));
  const ResultField field_b = read_result_vtu(result_file(b));
  Comparison c;
  c.nodes = static_cast<Index>(field_b.points.size());

  Vec3 lo = field_b.points.front(), hi = lo;
  for (const auto& x : field_b.points) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  bool same_cloud = field_a.points.size() == field_b.points.size();
  for (std::size_t i = 0; same_cloud && i < field_a.points.size(); ++i)
    same_cloud = (field_a.points[i] - field_b.points[i]).norm() <= 1e-9 * (hi - lo).norm();
  c.interpolated = !same_cloud;
  const std::vector<Vec3> u_a = same_cloud ? field_a.displacement
                                           : interpolate_displacements(field_a.points, field_a.displacement,
                                                                       field_b.points, catalog);
  Vec3 u_min = field_b.displacement.front(), u_max = u_min, sum_squares = Vec3::Zero();
  c.differences.resize(field_b.points.size());
  for (std::size_t i = 0; i < field_b.points.size(); ++i) {
    const Vec3 d = u_a[i] - field_b.displacement[i];
    c.differences[i] = d;
    sum_squares += d.cwiseProduct(d);
    c.max_abs_difference = c.max_abs_difference.cwiseMax(d.cwiseAbs());
    u_min = u_min.cwiseMin(field_b.displacement[i]);
    u_max = u_max.cwiseMax(field_b.displacement[i]);
  }
  c.range = u_max - u_min;
  for (int k = 0; k < 3; ++k) {
    c.rmse[k] = std::sqrt(sum_squares[k] / static_cast<double>(c.nodes));
    c.nrmse[k] = c.range[k] > 0.0 ? c.rmse[k] / c.range[k] : (c.rmse[k] == 0.0 ? 0.0 : INFINITY);
  }
  return c;
}

}  // namespace mtled
