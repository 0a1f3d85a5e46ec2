#pragma once
// Comparing two runs' displacement fields, as the paper does (Tables 3 and 4, Figs. 10, 12, 21, 23):
// A's interpolated displacements are carried onto B's nodes (MLS when the clouds differ) and the
// node-by-node differences summarised per component.
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "mtled/json.hpp"
#include "mtled/analysis/result_file.hpp"
#include "mtled/plugin_catalog.hpp"

namespace mtled {

struct Comparison {
  std::filesystem::path file_a, file_b;  // the result files read
  Index nodes = 0;            // B's nodes, where the fields are compared
  Index nodes_a = 0;          // A's nodes
  bool interpolated = false;  // true when A was interpolated onto B's nodes (different clouds)
  // Per component x, y, z. NRMSE = RMSE(u_A - u_B) / (max u_B - min u_B), RMSE = sqrt(mean of squares):
  // the usual normalised root-mean-square error (the paper prints the 1/N outside the root; we read that
  // as a typo: with it the value would shrink with the node count).
  Vec3 nrmse = Vec3::Zero();
  Vec3 rmse = Vec3::Zero();
  Vec3 max_abs_difference = Vec3::Zero();
  Vec3 range = Vec3::Zero();  // max - min of B's component
  std::vector<Vec3> differences;  // u_A - u_B at each of B's nodes (m)
};

// The definition compare_runs computes, in words (for reports and compare --json).
extern const char* const kNrmseDefinition;

// `a` and `b` are run folders (holding result.vtu) or result .vtu files. Interpolation uses the catalog's
// "mls" shape functions (linear basis) on A's nodes, each with a support radius of 1.3 times the distance
// to its 10th nearest neighbour (about 20 nodes per support). A missing folder or result file, or a
// folder whose run did not finish, throws InputError naming the path.
Comparison compare_runs(const std::filesystem::path& a, const std::filesystem::path& b, PluginCatalog& catalog);

// What `mtled compare --json` prints: nrmse, rmse_m, max_abs_difference_m, range_m (each {ux, uy, uz}),
// abs_difference_quantiles_m (p50, p90, p99 of |u_A - u_B|, nearest rank, each {ux, uy, uz, magnitude}),
// nrmse_paper_formula, definition, nodes {a, b, compared}, interpolated, interpolation, run_a, run_b.
json comparison_json(const Comparison& comparison);

// The displacement differences of A carried onto points: exposed for tests.
std::vector<Vec3> interpolate_displacements(const std::vector<Vec3>& nodes, const std::vector<Vec3>& displacement,
                                            const std::vector<Vec3>& points, PluginCatalog& catalog);

// Histograms of a comparison's node-by-node differences, one panel per component (SVG; the paper's Figs. 10,
// 12, 21 and 23).
void write_comparison_histograms(std::ostream& out, const Comparison& comparison, const std::string& name_a,
                                 const std::string& name_b, int bins);

}  // namespace mtled
