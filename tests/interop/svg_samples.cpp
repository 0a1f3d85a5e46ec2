// Writes the figures of `mtled study`, `mtled compare` and `mtled fit` for ordinary and for awkward input (long titles and
// paths, crowded points, labels near the legend, zero errors, tiny ranges) into a folder, through the same
// functions the commands use; tests/interop/figures_render.py draws them with a real SVG renderer and checks
// their layout.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "mtled/analysis/svg.hpp"

namespace fs = std::filesystem;
using namespace mtled::svg;

namespace {

void write(const fs::path& file, const auto& draw) {
  std::ofstream out(file);
  draw(out);
}

std::vector<PlotPoint> sweep(int n, double spread, const std::string& prefix) {
  std::vector<PlotPoint> points;
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * std::pow(spread, i / double(std::max(n - 1, 1)));
    points.push_back({prefix + std::to_string(500 * (i + 1)), t, 0.02 / std::sqrt(t) * (1 + 0.05 * (i % 3)), i % 3 == 0});
  }
  return points;
}

std::vector<double> normal_like(int n, double scale) {
  std::vector<double> values;
  for (int i = 0; i < n; ++i) values.push_back(scale * std::sin(0.37 * i) * std::cos(0.11 * i));
  return values;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: svg_samples FOLDER\n";
    return 2;
  }
  const fs::path folder = argv[1];
  fs::create_directories(folder);
  const std::string metric = "NRMSE of the displacement against the reference run";
  write(folder / "study_typical.svg", [&](std::ostream& o) {
    write_loglog_plot(o, sweep(4, 30.0, "target_nodes="), "Needle insertion: error against wall time",
                      "wall time of the run (s)", metric, {});
  });
  write(folder / "study_crowded.svg", [&](std::ostream& o) {
    // Twelve points within a factor 1.5 in time (labels compete for room), the slowest at the legend's side.
    auto points = sweep(12, 1.5, "discretisation/support_radius_factor=2.5,integrator/time_step_factor=");
    points.push_back({"reference_like_run_with_a_long_name", 3.0, 0.0, false});
    write_loglog_plot(o, points,
                      "A study whose description is much longer than the figure is wide, as users write them: "
                      "mesh refinement and time-step factor against the finest grid, brain phantom, 100 mm",
                      "wall time of the run (s)",
                      "relative error of the needle force at the final depth against the refined reference (1)",
                      {"not plotted: target_nodes=64000 (unstable: time_step_above_stable at step 1205, the "
                       "stable step re-estimated 0.67 times the setup estimate)",
                       "not plotted: target_nodes=128000 (error: out of memory)"});
  });
  write(folder / "histograms_typical.svg", [&](std::ostream& o) {
    write_histograms(o,
                     {{"u_x: NRMSE 1.2e-03, max |diff| 3.4e-06 m", "u_x(A) - u_x(B) (m)", normal_like(2000, 3e-6)},
                      {"u_y: NRMSE 9.8e-04, max |diff| 2.1e-06 m", "u_y(A) - u_y(B) (m)", normal_like(2000, 2e-6)},
                      {"u_z: NRMSE 2.2e-03, max |diff| 1.1e-05 m", "u_z(A) - u_z(B) (m)", normal_like(2000, 1e-5)}},
                     "Node-by-node displacement differences, A = runs/coarse, B = runs/fine",
                     "2000 nodes of B; NRMSE = RMSE(u_A - u_B) / (max u_B - min u_B)", 40);
  });
  write(folder / "histograms_long.svg", [&](std::ostream& o) {
    const std::string long_path = "/home/someone/projects/needle-insertion/studies/brain_phantom_refinement/runs/";
    write_histograms(o,
                     {{"u_x: NRMSE 1.234e-13, max |diff| 1.234e-17 m", "u_x(A) - u_x(B) (m)", normal_like(500, 1.2e-17)},
                      {"u_y: NRMSE 0, max |diff| 0 m", "u_y(A) - u_y(B) (m)", std::vector<double>(500, 0.0)},
                      {"u_z: NRMSE 4.5e-01, max |diff| 1.0e+02 m", "u_z(A) - u_z(B) (m)", normal_like(500, -123.4)}},
                     "Node-by-node displacement differences, A = " + long_path + "target_nodes=4000, B = " + long_path +
                         "target_nodes=64000",
                     "64000 nodes of B, A (4000 nodes) interpolated onto them with MLS; NRMSE = RMSE(u_A - u_B) / "
                     "(max u_B - min u_B), RMSE = sqrt(mean of squares)",
                     25);
  });
  write(folder / "fit_typical.svg", [&](std::ostream& o) {
    XyPanel force{"compression: R^2 0.9998", "top displacement (mm)", "force (N): measured o, fitted -", {}, {}, {}, {}};
    XyPanel markers{"xray_8mm: R^2 0.977", "measured displacement component (mm)", "fitted (mm)", {}, {}, {}, {}};
    for (int i = 1; i <= 8; ++i) {
      force.x_points.push_back(-0.5 * i);
      force.y_points.push_back(-0.012 * i * i * (1.0 + 0.01 * std::sin(i)));
      force.x_line.push_back(-0.5 * i);
      force.y_line.push_back(-0.012 * i * i);
    }
    for (int i = 0; i < 120; ++i) {
      markers.x_points.push_back(-2.5 * std::sin(0.3 * i) * std::exp(-0.01 * i));
      markers.y_points.push_back(markers.x_points.back() + 0.05 * std::cos(1.7 * i));
    }
    markers.identity_line = true;
    write_xy_panels(o, {force, markers}, "Measured against fitted",
                    "C_D = 0.3983 +- 0.0049, puncture_strain = 1.4e-05 +- inf (1 sigma)");
  });
  write(folder / "fit_awkward.svg", [&](std::ostream& o) {
    // One datum, a flat curve, a title longer than the panel, numbers of every size.
    XyPanel single{"an experiment whose name is much longer than its panel is wide: semi-confined compression at "
                   "the rims, third batch of gel, R^2 nan",
                   "needle depth (mm)", "force (N): measured o, fitted -", {15.0}, {1.234e-7}, {15.0}, {1.234e-7}};
    XyPanel flat{"flat: R^2 0", "needle depth (mm)", "force (N)", {1, 2, 3}, {5, 5, 5}, {1, 2, 3}, {5, 5, 5}};
    write_xy_panels(o, {single, flat}, "Measured against fitted: a fit whose description is much longer than the "
                    "figure is wide, as users write them, with every parameter's name spelled out",
                    "mu = 712 +- 7.7, alpha = -1.331 +- 0.21, D = 5.57738e-05 +- 1.2e-03 (1 sigma)");
  });
  return 0;
}
