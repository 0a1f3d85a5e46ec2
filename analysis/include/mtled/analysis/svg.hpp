#pragma once
// Hand-written SVG figures for `mtled compare` (histograms of node-by-node differences, like the paper's
// Figs. 10, 12, 21 and 23) and `mtled study` (error against wall time, log-log, with the Pareto front).
// Plain SVG 1.1 with text labels, readable in any browser without tools.
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace mtled::svg {

// Escapes &, <, >, " and ' for XML text and attribute values.
std::string escape(std::string_view text);

// One histogram panel: the counts of `values` in `bins` equal bins spanning [min, max] (widened to hold 0).
struct HistogramPanel {
  std::string title;    // e.g. "u_x: NRMSE 1.2e-03"
  std::string x_label;  // e.g. "u_A - u_B (m)"
  std::vector<double> values;
};
// Panels side by side under a heading (and an optional second line of smaller text).
void write_histograms(std::ostream& out, const std::vector<HistogramPanel>& panels, const std::string& heading,
                      const std::string& subheading, int bins);

struct PlotPoint {
  std::string label;
  double x = 0.0;  // > 0
  double y = 0.0;  // >= 0 (0 is drawn on the bottom axis and labelled so)
  bool front = false;
};
// A log-log scatter plot: points on the front filled and joined by a staircase, the others hollow; a
// legend; `notes` (e.g. failed configurations) listed under the plot.
void write_loglog_plot(std::ostream& out, const std::vector<PlotPoint>& points, const std::string& title,
                       const std::string& x_label, const std::string& y_label, const std::vector<std::string>& notes);

// Linear x-y panels side by side: measured points as circles, a fitted curve as a line, and optionally the line
// y = x (for measured against predicted values).
struct XyPanel {
  std::string title, x_label, y_label;
  std::vector<double> x_points, y_points;
  std::vector<double> x_line, y_line;
  bool identity_line = false;
};
void write_xy_panels(std::ostream& out, const std::vector<XyPanel>& panels, const std::string& heading,
                     const std::string& subheading);

}  // namespace mtled::svg
