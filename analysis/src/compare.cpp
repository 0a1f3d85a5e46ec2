#include "mtled/analysis/compare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "mtled/errors.hpp"
#include "mtled/analysis/mls_transfer.hpp"
#include "mtled/analysis/result_file.hpp"
#include "mtled/analysis/svg.hpp"
#include "mtled/mesh.hpp"
#include "mtled/point_search.hpp"

namespace fs = std::filesystem;

namespace mtled {

const char* const kNrmseDefinition =
    "NRMSE = RMSE(u_A - u_B) / (max u_B - min u_B) per displacement component over B's nodes, "
    "RMSE = sqrt(mean of the squared node-by-node differences); A is interpolated onto B's nodes (MLS) when "
    "the node clouds differ. The paper prints the 1/N outside the root (a typo: that value shrinks with the "
    "node count); nrmse_paper_formula gives that literal value, NRMSE / sqrt(N).";

std::vector<Vec3> interpolate_displacements(const std::vector<Vec3>& nodes, const std::vector<Vec3>& displacement,
                                            const std::vector<Vec3>& points, PluginCatalog& catalog) {
  const MlsTransfer transfer(nodes, catalog);
  std::vector<Vec3> out;
  out.reserve(points.size());
  for (const Vec3& x : points) out.push_back(transfer.at(x, displacement));
  return out;
}

Comparison compare_runs(const fs::path& a, const fs::path& b, PluginCatalog& catalog) {
  Comparison c;
  c.file_a = result_file_of(a);
  c.file_b = result_file_of(b);
  const ResultField field_a = read_result_vtu(c.file_a);
  const ResultField field_b = read_result_vtu(c.file_b);
  c.nodes = static_cast<Index>(field_b.points.size());
  c.nodes_a = static_cast<Index>(field_a.points.size());

  const auto [lo, hi] = bounding_box(field_b.points);
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

namespace {

// Nearest-rank quantiles of |u_A - u_B| per component and of its magnitude: how much of the body lies
// within a given distance, which the RMS and the maximum alone do not say (the paper reads its histograms
// against the 1-2 mm of surgical accuracy).
json difference_quantiles(const std::vector<Vec3>& differences) {
  const std::size_t n = differences.size();
  std::vector<std::vector<double>> columns(4, std::vector<double>(n));
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) columns[static_cast<std::size_t>(k)][i] = std::abs(differences[i][k]);
    columns[3][i] = differences[i].norm();
  }
  for (auto& column : columns) std::sort(column.begin(), column.end());
  static const char* const kNames[] = {"ux", "uy", "uz", "magnitude"};
  json quantiles = json::object();
  for (const int percent : {50, 90, 99}) {
    json row = json::object();
    // The smallest value with at least `percent`% of the nodes at or under it.
    const std::size_t rank = (static_cast<std::size_t>(percent) * n + 99) / 100;
    for (std::size_t k = 0; k < 4; ++k) row[kNames[k]] = n == 0 ? 0.0 : columns[k][std::max<std::size_t>(rank, 1) - 1];
    quantiles[fmt::format("p{}", percent)] = row;
  }
  return quantiles;
}

}  // namespace

json comparison_json(const Comparison& c) {
  auto components = [](const Vec3& v) { return json{{"ux", v[0]}, {"uy", v[1]}, {"uz", v[2]}}; };
  const double root_n = std::sqrt(static_cast<double>(std::max<Index>(c.nodes, 1)));
  return {{"nrmse", components(c.nrmse)},
          {"rmse_m", components(c.rmse)},
          {"max_abs_difference_m", components(c.max_abs_difference)},
          {"abs_difference_quantiles_m", difference_quantiles(c.differences)},
          {"range_m", components(c.range)},
          {"nrmse_paper_formula", components(c.nrmse / root_n)},
          {"definition", kNrmseDefinition},
          {"nodes", {{"a", c.nodes_a}, {"b", c.nodes}, {"compared", c.nodes}}},
          {"interpolated", c.interpolated},
          {"interpolation", c.interpolated ? json("mls, linear basis, on A's nodes; support radius 1.3 x the distance "
                                                  "to the 10th nearest node of A")
                                           : json(nullptr)},
          {"run_a", c.file_a.string()},
          {"run_b", c.file_b.string()}};
}

void write_comparison_histograms(std::ostream& out, const Comparison& c, const std::string& name_a,
                                 const std::string& name_b, int bins) {
  static const char* const kComponents[] = {"u_x", "u_y", "u_z"};
  std::vector<svg::HistogramPanel> panels(3);
  for (int k = 0; k < 3; ++k) {
    panels[static_cast<std::size_t>(k)].title =
        fmt::format("{}: NRMSE {:.3g}, max |diff| {:.3g} m", kComponents[k], c.nrmse[k], c.max_abs_difference[k]);
    panels[static_cast<std::size_t>(k)].x_label = fmt::format("{0}(A) - {0}(B) (m)", kComponents[k]);
    panels[static_cast<std::size_t>(k)].values.reserve(c.differences.size());
    for (const Vec3& d : c.differences) panels[static_cast<std::size_t>(k)].values.push_back(d[k]);
  }
  const std::string heading = fmt::format("Node-by-node displacement differences, A = {}, B = {}", name_a, name_b);
  const std::string subheading =
      fmt::format("{} nodes of B{}; NRMSE = RMSE(u_A - u_B) / (max u_B - min u_B), RMSE = sqrt(mean of squares)",
                  c.nodes, c.interpolated ? fmt::format(", A ({} nodes) interpolated onto them with MLS", c.nodes_a) : "");
  svg::write_histograms(out, panels, heading, subheading, bins);
}

}  // namespace mtled
