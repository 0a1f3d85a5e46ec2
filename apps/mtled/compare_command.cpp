// mtled compare: NRMSE per displacement component between two runs (the paper's Tables 3 and 4), a table
// or JSON, and histograms of the node-by-node differences (the paper's Figs. 10, 12, 21, 23) as SVG.
#include <fmt/format.h>

#include <fstream>
#include <iostream>

#include "commands.hpp"
#include "mtled/analysis/compare.hpp"
#include "mtled/errors.hpp"
#include "mtled/log.hpp"

namespace fs = std::filesystem;

namespace mtled::app {

int compare_command(const CompareOptions& options, const std::vector<fs::path>& plugin_paths) {
  if (options.bins < 1) throw InputError("--bins", "must be at least 1");
  PluginCatalog catalog(plugin_search_path(plugin_paths, {}));
  const Comparison c = compare_runs(options.a, options.b, catalog);

  if (!options.histogram.empty()) {
    const fs::path file = options.histogram;
    if (!file.parent_path().empty()) {
      std::error_code ec;
      fs::create_directories(file.parent_path(), ec);
    }
    const fs::path temporary = file.parent_path() / ("." + file.filename().string() + ".tmp");
    {
      std::ofstream out(temporary, std::ios::binary);
      if (!out) throw InputError(file.string(), "cannot write the histogram file");
      write_comparison_histograms(out, c, options.a.string(), options.b.string(), options.bins);
      if (!out.flush()) throw std::runtime_error(fmt::format("writing {} failed (disk full?)", file.string()));
    }
    fs::rename(temporary, file);
  }

  if (options.json) {
    json report = comparison_json(c);
    report["histogram"] = options.histogram.empty() ? json(nullptr) : json(options.histogram.string());
    std::cout << report.dump(2) << "\n";
    return 0;
  }
  std::cout << fmt::format("A: {} ({} nodes)\nB: {} ({} nodes)\n", c.file_a.string(), c.nodes_a, c.file_b.string(),
                           c.nodes);
  std::cout << (c.interpolated ? "A's displacements interpolated onto B's nodes with MLS (the clouds differ)\n"
                               : "same node cloud: compared node by node\n");
  std::cout << fmt::format("\n{:<10} {:>12} {:>12} {:>18} {:>16}\n", "component", "NRMSE", "RMSE (m)",
                           "max |u_A-u_B| (m)", "range of u_B (m)");
  static const char* const kNames[] = {"ux", "uy", "uz"};
  for (int k = 0; k < 3; ++k)
    std::cout << fmt::format("{:<10} {:>12.4e} {:>12.4e} {:>18.4e} {:>16.4e}\n", kNames[k], c.nrmse[k], c.rmse[k],
                             c.max_abs_difference[k], c.range[k]);
  std::cout << fmt::format("\nNRMSE = RMSE(u_A - u_B) / (max u_B - min u_B) over B's {} nodes, RMSE = sqrt(mean of "
                           "squares)\n(the paper prints 1/N outside the root; that literal value is NRMSE / sqrt(N): "
                           "see --json, nrmse_paper_formula)\n",
                           c.nodes);
  if (!options.histogram.empty()) std::cout << "histograms: " << options.histogram.string() << "\n";
  return 0;
}

}  // namespace mtled::app
