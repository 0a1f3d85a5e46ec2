// The partition of a scene's cloud into 2 to 512 parts as the mpi backend makes it (METIS on the tets' dual
// graph), and a strong-scaling projection from those sizes and a one-rank run's measured costs.
//
//   build/bin/mtled_partition_study SCENE RUN_FOLDER [PARTS...] [--latency-us 2] [--bandwidth-GBs 10]
//
// RUN_FOLDER: a one-process run of the same scene (its summary.json: the force kernel's time per evaluation, the
// steps and evaluations, the solve time). Prints one row per part count: integration points per part (the largest
// over the mean: the imbalance), ghost nodes per part (mean and largest), the largest share of boundary points
// (whose supports reach a ghost node: computed before the halo is sent), neighbours, the bytes a rank sends and
// receives per force evaluation and per step (24 per ghost node each: its force contribution out, its displacement
// in), the bytes of a whole-displacement gather (24 per node it does not own; on the steps the monitors read it), and
// the projected time per step on that many ranks of the run's threads (the model: docs/mpi.md; the run's
// backend.update_s, the per-node work and the constraint products, is divided between the ranks, the rest of its
// step repeated).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <cstdlib>
#include <iostream>
#include <numeric>
#include <string>

#include "mesh_partition.hpp"
#include "mtled/analysis/scene_sections.hpp"
#include "mtled/json.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"

namespace {

struct Costs {
  double kernel_s = 0.0;             // one force evaluation on one rank
  double update_per_step_s = 0.0;    // the per-node work and the constraint products, which the ranks divide
  double repeated_per_step_s = 0.0;  // the step's other work (the solve, drivers, monitors), which every rank repeats
  double evaluations_per_step = 1.0;
};

Costs measured_costs(const std::filesystem::path& run) {
  std::ifstream in(run / "summary.json");
  if (!in) throw std::runtime_error("cannot read " + (run / "summary.json").string());
  const mtled::json s = mtled::json::parse(in);
  Costs c;
  const double steps = s.at("steps").get<double>(), evaluations = s.at("backend").at("force_evaluations").get<double>();
  c.kernel_s = s.at("backend").at("force_kernel_s").get<double>();
  c.evaluations_per_step = evaluations / steps;
  const double update_s = s.at("backend").value("update_s", 0.0);
  c.update_per_step_s = update_s / steps;
  c.repeated_per_step_s = (s.at("solve_time_s").get<double>() - c.kernel_s * evaluations - update_s) / steps;
  return c;
}

}  // namespace

int study(int argc, char** argv);

int main(int argc, char** argv) {
  try {
    return study(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "mtled_partition_study: " << e.what() << "\n";
    return 2;
  }
}

// What a part count costs besides the kernel's own work: the network and what crosses it each step.
struct Exchange {
  double latency_s, bandwidth;  // per message, bytes per second
  double product_bytes;         // the constraint products summed over the ranks every step
  long whole_every;             // steps between reads of the whole displacement (0: never)
};

// One table row: the partition into n parts and the step time it projects.
void print_row(const mtled::Discretisation& model, const Costs& costs, const Exchange& exchange, double one_rank,
               int n) {
  using namespace mtled;
  const double latency_s = exchange.latency_s, bandwidth = exchange.bandwidth;
  const double product_bytes = exchange.product_bytes;
  const long whole_every = exchange.whole_every;
  const auto nodes = static_cast<double>(model.node_count());
  const MeshPartition partition = partition_mesh(model.mesh(), n);
  std::vector<int> point_part(static_cast<std::size_t>(model.points().count()));
  for (std::size_t p = 0; p < point_part.size(); ++p)
    point_part[p] = partition.tet_part[static_cast<std::size_t>(model.points().tets[p])];
  const PartSizes sizes = part_sizes(partition, point_part, model.gradients());
  const double mean_points = static_cast<double>(model.points().count()) / n;
  const double imbalance =
      static_cast<double>(*std::max_element(sizes.points.begin(), sizes.points.end())) / mean_points;
  const double mean_ghosts =
      static_cast<double>(std::accumulate(sizes.ghost_nodes.begin(), sizes.ghost_nodes.end(), std::int64_t{0})) / n;
  const auto most_ghosts = static_cast<double>(*std::max_element(sizes.ghost_nodes.begin(), sizes.ghost_nodes.end()));
  const int neighbours = *std::max_element(sizes.neighbours.begin(), sizes.neighbours.end());
  const auto fewest_owned = static_cast<double>(*std::min_element(sizes.owned_nodes.begin(), sizes.owned_nodes.end()));
  const double halo_bytes = 24.0 * most_ghosts, gather_bytes = 24.0 * (nodes - fewest_owned);
  double boundary_share = 0.0;
  for (int q = 0; q < n; ++q)
    if (sizes.points[static_cast<std::size_t>(q)] > 0)
      boundary_share =
          std::max(boundary_share, static_cast<double>(sizes.boundary_points[static_cast<std::size_t>(q)]) /
                                       static_cast<double>(sizes.points[static_cast<std::size_t>(q)]));
  // Per evaluation, the slowest rank: the kernel over its boundary points; then its halo (one message per
  // neighbour, the bytes over the link) while it computes its interior, whichever takes longer; then one reduction
  // (log2 n rounds).
  const double kernel = costs.kernel_s * imbalance / n;
  const double halo = neighbours * latency_s + halo_bytes / bandwidth;
  const double reduction = std::ceil(std::log2(n)) * latency_s;
  const double evaluation = kernel * boundary_share + std::max(halo, kernel * (1.0 - boundary_share)) + reduction;
  // Per step: the rank's own nodes' update (the most-owning rank's share), the repeated rest, and the exchanges
  // of the step: the prediction's and the step sums' reductions and the drivers' gather (a few dozen nodes:
  // latency), the constraint products' sum (a reduce-scatter, one message to each other rank, and a gather: twice
  // the products' bytes), the ghost nodes' displacements (as the halo, not hidden), and the whole displacement on
  // one step in whole_every.
  const double most_owned = static_cast<double>(*std::max_element(sizes.owned_nodes.begin(), sizes.owned_nodes.end()));
  const double update = costs.update_per_step_s * most_owned / nodes;
  const double whole = 2.0 * std::ceil(std::log2(n)) * latency_s + gather_bytes / bandwidth;
  const double products = (n - 1) * latency_s + reduction + 2.0 * product_bytes / bandwidth;
  const double exchanges =
      3.0 * reduction + products + halo + (whole_every > 0 ? whole / static_cast<double>(whole_every) : 0.0);
  const double step = costs.evaluations_per_step * evaluation + update + costs.repeated_per_step_s + exchanges;
  fmt::print("| {} | {:.3f} | {:.0f} / {:.0f} | {:.0f}% | {} | {:.1f} | {:.0f} | {:.3f} | {:.1f}x |\n", n, imbalance,
             mean_ghosts, most_ghosts, 100.0 * boundary_share, neighbours, halo_bytes / 1e3, gather_bytes / 1e3,
             step * 1e3, one_rank / step);
}

int study(int argc, char** argv) {
  using namespace mtled;
  std::vector<std::string> args(argv + 1, argv + argc);
  double latency_s = 2e-6, bandwidth = 10e9;
  std::vector<int> parts;
  std::vector<std::string> positional;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--latency-us" && i + 1 < args.size()) latency_s = std::stod(args[++i]) * 1e-6;
    else if (args[i] == "--bandwidth-GBs" && i + 1 < args.size()) bandwidth = std::stod(args[++i]) * 1e9;
    else if (positional.size() < 2) positional.push_back(args[i]);
    else parts.push_back(std::stoi(args[i]));
  }
  if (positional.size() < 2) {
    std::cerr << "usage: mtled_partition_study SCENE RUN_FOLDER [PARTS...] [--latency-us 2] [--bandwidth-GBs 10]\n";
    return 2;
  }
  if (parts.empty()) parts = {2, 4, 8, 16, 32, 64, 128, 256, 512};
  const Costs costs = measured_costs(positional[1]);

  SceneDocument document = read_scene(positional[0]);
  PluginCatalog catalog(plugin_search_path({}, scene_plugin_paths(document)));
  const Scene scene = validate_scene(std::move(document), catalog, run_scene_sections());
  const Simulation simulation(scene, catalog);
  const Discretisation& model = simulation.system().discretisation();
  // The steps on which a monitor reads the whole displacement: the fold check's (the most frequent; the stable-step
  // estimate's are rarer), or the snapshots' when more frequent.
  // The constraint products summed over the ranks every step: 8 bytes per constrained row and component.
  double product_bytes = 0.0;
  for (const NodalConstraints* set : simulation.system().constraint_sets())
    product_bytes += 8.0 * static_cast<double>(set->size()) *
                     static_cast<double>(std::count(set->components().begin(), set->components().end(), true));
  long whole_every = scene.section("monitors").integer("inversion_every_steps");
  if (const long snapshots = scene.section("output").integer("every_steps"); snapshots > 0)
    whole_every = whole_every > 0 ? std::min(whole_every, snapshots) : snapshots;
  fmt::print(
      "{}: {} nodes, {} integration points; one rank: force kernel {:.3f} ms per evaluation, {:.2f} "
      "evaluations per step, the update {:.3f} ms and the rest {:.3f} ms per step; network assumed {:.1f} us, "
      "{:.1f} GB/s; the whole displacement gathered every {} steps, {:.0f} KB of constraint products summed per step\n",
      positional[0], model.node_count(), model.points().count(), costs.kernel_s * 1e3, costs.evaluations_per_step,
      costs.update_per_step_s * 1e3, costs.repeated_per_step_s * 1e3, latency_s * 1e6, bandwidth / 1e9, whole_every,
      product_bytes / 1e3);
  fmt::print("| parts | imbalance | ghost nodes per part (mean / largest) | boundary points (largest share) | neighbours "
             "(largest) | halo KB per evaluation and per step (largest rank) | whole gather KB (largest rank) | projected "
             "ms per step | speed-up |\n");
  fmt::print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  const double one_rank = costs.evaluations_per_step * costs.kernel_s + costs.update_per_step_s + costs.repeated_per_step_s;
  for (const int n : parts) print_row(model, costs, {latency_s, bandwidth, product_bytes, whole_every}, one_rank, n);
  return 0;
}
