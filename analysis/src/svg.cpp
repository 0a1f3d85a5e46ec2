#include "mtled/analysis/svg.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace mtled::svg {

namespace {

constexpr const char* kFont = "font-family=\"Helvetica, Arial, sans-serif\"";

// About `target` ticks at 1, 2 or 5 times a power of ten, inside [lo, hi].
std::vector<double> linear_ticks(double lo, double hi, int target = 5) {
  const double span = hi - lo;
  if (!(span > 0.0) || !std::isfinite(span)) return {lo};
  const double raw = span / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / magnitude;
  const double step = (r < 1.5 ? 1.0 : r < 3.0 ? 2.0 : r < 7.0 ? 5.0 : 10.0) * magnitude;
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step)
    ticks.push_back(std::abs(t) < 1e-9 * step ? 0.0 : t);
  return ticks;
}

// Labelled ticks of a log axis over [lo, hi]: the decades, then 2 and 5 times them, then every integer
// multiple, until at least three fall inside.
std::vector<double> log_ticks(double lo, double hi) {
  const int first = static_cast<int>(std::floor(std::log10(lo))), last = static_cast<int>(std::ceil(std::log10(hi)));
  for (const std::vector<int>& multiples : {std::vector<int>{1}, std::vector<int>{1, 2, 5}, std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9}}) {
    std::vector<double> ticks;
    for (int k = first; k <= last; ++k)
      for (int m : multiples) {
        const double t = m * std::pow(10.0, k);
        if (t >= lo * (1 - 1e-12) && t <= hi * (1 + 1e-12)) ticks.push_back(t);
      }
    if (ticks.size() >= 3 || multiples.size() == 9) return ticks;
  }
  return {};
}

std::string number(double v) { return fmt::format("{:.3g}", v); }

}  // namespace

std::string escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        // Control characters are not allowed in XML 1.0.
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\n' || c == '\t') out += c;
    }
  }
  return out;
}

void write_histograms(std::ostream& out, const std::vector<HistogramPanel>& panels, const std::string& heading,
                      const std::string& subheading, int bins) {
  bins = std::max(bins, 1);
  const double panel_w = 380, panel_h = 330, top = 64;
  const double left = 62, right = 28, upper = 34, lower = 56;  // margins inside a panel
  const double width = panel_w * static_cast<double>(std::max<std::size_t>(panels.size(), 1)), height = top + panel_h;
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out << fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{0}\" height=\"{1}\" "
                     "viewBox=\"0 0 {0} {1}\" {2} font-size=\"12\">\n",
                     width, height, kFont);
  out << fmt::format("<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"white\"/>\n", width, height);
  out << fmt::format("<text x=\"{}\" y=\"24\" text-anchor=\"middle\" font-size=\"16\">{}</text>\n", width / 2,
                     escape(heading));
  if (!subheading.empty())
    out << fmt::format("<text x=\"{}\" y=\"44\" text-anchor=\"middle\" font-size=\"11\" fill=\"#444\">{}</text>\n",
                       width / 2, escape(subheading));

  for (std::size_t p = 0; p < panels.size(); ++p) {
    const auto& panel = panels[p];
    const double x0 = static_cast<double>(p) * panel_w + left, x1 = (static_cast<double>(p) + 1) * panel_w - right;
    const double y0 = top + upper, y1 = top + panel_h - lower;  // plot area, y1 is the bottom
    double lo = 0.0, hi = 0.0;
    for (double v : panel.values)
      if (std::isfinite(v)) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    if (!(hi - lo > 0.0)) {  // every difference is 0: a narrow window around it
      lo = -1e-9;
      hi = 1e-9;
    }
    const double bin_width = (hi - lo) / bins;
    std::vector<long> counts(static_cast<std::size_t>(bins), 0);
    long total = 0;
    for (double v : panel.values) {
      if (!std::isfinite(v)) continue;
      const auto b = std::clamp(static_cast<long>(std::floor((v - lo) / bin_width)), 0L, static_cast<long>(bins - 1));
      ++counts[static_cast<std::size_t>(b)];
      ++total;
    }
    const long most = std::max(1L, *std::max_element(counts.begin(), counts.end()));
    const auto y_ticks = linear_ticks(0.0, static_cast<double>(most), 5);
    const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : 1.0;
    const double y_top = std::max(static_cast<double>(most), std::ceil(static_cast<double>(most) / y_step) * y_step);
    auto sx = [&](double v) { return x0 + (v - lo) / (hi - lo) * (x1 - x0); };
    auto sy = [&](double c) { return y1 - c / y_top * (y1 - y0); };

    out << fmt::format("<g id=\"panel{}\">\n", p);
    out << fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"13\">{}</text>\n", (x0 + x1) / 2,
                       y0 - 12, escape(panel.title));
    // Grid and y ticks.
    for (double t : y_ticks) {
      out << fmt::format("<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"#ddd\"/>\n", x0, sy(t), x1,
                         sy(t));
      out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"end\" font-size=\"10\">{}</text>\n", x0 - 5,
                         sy(t) + 3.5, fmt::format("{:g}", t));
    }
    // Bars.
    for (int b = 0; b < bins; ++b) {
      const long c = counts[static_cast<std::size_t>(b)];
      if (c == 0) continue;
      const double left_edge = sx(lo + b * bin_width), right_edge = sx(lo + (b + 1) * bin_width);
      out << fmt::format("<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" fill=\"#4a7ab5\" "
                         "stroke=\"#2a4a75\" stroke-width=\"0.5\"><title>{} to {}: {} nodes</title></rect>\n",
                         left_edge, sy(static_cast<double>(c)), std::max(right_edge - left_edge, 0.5),
                         y1 - sy(static_cast<double>(c)), number(lo + b * bin_width), number(lo + (b + 1) * bin_width),
                         c);
    }
    // Zero line, axes, x ticks.
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\" stroke=\"#c33\" "
                       "stroke-dasharray=\"4 3\"/>\n",
                       sx(0.0), y0, y1);
    out << fmt::format("<path d=\"M {:.2f} {:.2f} V {:.2f} H {:.2f}\" fill=\"none\" stroke=\"black\"/>\n", x0, y0, y1, x1);
    for (double t : linear_ticks(lo, hi, 4)) {
      out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\" stroke=\"black\"/>\n", sx(t),
                         y1, y1 + 4);
      out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\" font-size=\"10\">{}</text>\n", sx(t),
                         y1 + 16, fmt::format("{:.3g}", t));
    }
    out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\">{}</text>\n", (x0 + x1) / 2, y1 + 36,
                       escape(panel.x_label));
    out << fmt::format("<text transform=\"translate({:.2f} {:.2f}) rotate(-90)\" text-anchor=\"middle\">number of "
                       "nodes ({} in all)</text>\n",
                       x0 - 44, (y0 + y1) / 2, total);
    out << "</g>\n";
  }
  out << "</svg>\n";
}

void write_loglog_plot(std::ostream& out, const std::vector<PlotPoint>& points, const std::string& title,
                       const std::string& x_label, const std::string& y_label, const std::vector<std::string>& notes) {
  const double width = 820, plot_h = 480, left = 90, right = 230, upper = 50, lower = 64;
  const double height = plot_h + 18.0 * static_cast<double>(notes.size()) + (notes.empty() ? 0 : 10);
  const double x0 = left, x1 = width - right, y0 = upper, y1 = plot_h - lower;

  double x_lo = std::numeric_limits<double>::infinity(), x_hi = 0.0;
  double y_lo = std::numeric_limits<double>::infinity(), y_hi = 0.0;
  bool has_zero = false;
  for (const auto& p : points) {
    if (!(p.x > 0.0) || !std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    x_lo = std::min(x_lo, p.x);
    x_hi = std::max(x_hi, p.x);
    if (p.y > 0.0) {
      y_lo = std::min(y_lo, p.y);
      y_hi = std::max(y_hi, p.y);
    } else {
      has_zero = true;
    }
  }
  if (!(x_hi > 0.0)) x_lo = 0.1, x_hi = 10.0;
  if (!(y_hi > 0.0)) y_lo = 1e-6, y_hi = 1.0;
  // Half a decade of room around the data, at least one decade in all.
  x_lo /= 1.6, x_hi *= 1.6, y_lo /= has_zero ? 10.0 : 1.6, y_hi *= 1.6;
  if (x_hi / x_lo < 10.0) {
    const double g = std::sqrt(10.0 / (x_hi / x_lo));
    x_lo /= g, x_hi *= g;
  }
  if (y_hi / y_lo < 10.0) {
    const double g = std::sqrt(10.0 / (y_hi / y_lo));
    y_lo /= g, y_hi *= g;
  }
  auto sx = [&](double v) { return x0 + std::log10(v / x_lo) / std::log10(x_hi / x_lo) * (x1 - x0); };
  auto sy = [&](double v) {
    return v > 0.0 ? y1 - std::log10(v / y_lo) / std::log10(y_hi / y_lo) * (y1 - y0) : y1;
  };

  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out << fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{0}\" height=\"{1}\" "
                     "viewBox=\"0 0 {0} {1}\" {2} font-size=\"12\">\n",
                     width, height, kFont);
  out << fmt::format("<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"white\"/>\n", width, height);
  out << fmt::format("<text x=\"{}\" y=\"26\" text-anchor=\"middle\" font-size=\"15\">{}</text>\n", (x0 + x1) / 2,
                     escape(title));
  // Grid lines and tick labels.
  out << "<g id=\"axes\">\n";
  for (double t : log_ticks(x_lo, x_hi)) {
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\" stroke=\"#ddd\"/>\n", sx(t), y0,
                       y1);
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\" stroke=\"black\"/>\n", sx(t), y1,
                       y1 + 5);
    out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\" font-size=\"11\">{:g}</text>\n", sx(t),
                       y1 + 18, t);
  }
  for (double t : log_ticks(y_lo, y_hi)) {
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{2:.2f}\" y2=\"{1:.2f}\" stroke=\"#ddd\"/>\n", x0, sy(t),
                       x1);
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{2:.2f}\" y2=\"{1:.2f}\" stroke=\"black\"/>\n", x0 - 5,
                       sy(t), x0);
    out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"end\" font-size=\"11\">{:g}</text>\n", x0 - 8,
                       sy(t) + 4, t);
  }
  out << fmt::format("<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" fill=\"none\" "
                     "stroke=\"black\"/>\n",
                     x0, y0, x1 - x0, y1 - y0);
  out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\">{}</text>\n", (x0 + x1) / 2, y1 + 42,
                     escape(x_label));
  out << fmt::format("<text transform=\"translate({:.2f} {:.2f}) rotate(-90)\" text-anchor=\"middle\">{}</text>\n",
                     x0 - 62, (y0 + y1) / 2, escape(y_label));
  out << "</g>\n";

  // The Pareto front as a staircase through its points (ordered by time).
  std::vector<const PlotPoint*> front;
  for (const auto& p : points)
    if (p.front && p.x > 0.0 && std::isfinite(p.y)) front.push_back(&p);
  std::sort(front.begin(), front.end(), [](const PlotPoint* a, const PlotPoint* b) { return a->x < b->x; });
  if (front.size() > 1) {
    std::string d = fmt::format("M {:.2f} {:.2f}", sx(front[0]->x), sy(front[0]->y));
    for (std::size_t i = 1; i < front.size(); ++i) d += fmt::format(" H {:.2f} V {:.2f}", sx(front[i]->x), sy(front[i]->y));
    out << fmt::format("<path id=\"pareto-front\" d=\"{}\" fill=\"none\" stroke=\"#c33\" stroke-width=\"1.5\" "
                       "stroke-dasharray=\"5 3\"/>\n",
                       d);
  }
  out << "<g id=\"points\">\n";
  for (const auto& p : points) {
    if (!(p.x > 0.0) || !std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    const double cx = sx(p.x), cy = sy(p.y);
    out << fmt::format("<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"5\" fill=\"{}\" stroke=\"{}\" stroke-width=\"1.5\" "
                       "class=\"{}\"><title>{}: {:.4g} s, error {:.4g}</title></circle>\n",
                       cx, cy, p.front ? "#c33" : "white", p.front ? "#c33" : "#555", p.front ? "front" : "dominated",
                       escape(p.label), p.x, p.y);
    out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" font-size=\"10\" fill=\"#333\">{}{}</text>\n", cx + 8, cy - 6,
                       escape(p.label), p.y > 0.0 ? "" : " (error 0)");
  }
  out << "</g>\n";

  // Legend, right of the plot.
  const double lx = x1 + 20, ly = y0 + 10;
  out << "<g id=\"legend\">\n";
  out << fmt::format("<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"5\" fill=\"#c33\" stroke=\"#c33\"/>\n", lx + 6, ly);
  out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\">Pareto front</text>\n", lx + 18, ly + 4);
  out << fmt::format("<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"#c33\" stroke-width=\"1.5\" "
                     "stroke-dasharray=\"5 3\"/>\n",
                     lx, ly + 20, lx + 12, ly + 20);
  out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\">front (staircase)</text>\n", lx + 18, ly + 24);
  out << fmt::format("<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"5\" fill=\"white\" stroke=\"#555\" "
                     "stroke-width=\"1.5\"/>\n",
                     lx + 6, ly + 40);
  out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\">dominated: another run</text>\n", lx + 18, ly + 44);
  out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\">is no slower and no less</text>\n", lx + 18, ly + 58);
  out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\">accurate</text>\n", lx + 18, ly + 72);
  out << "</g>\n";

  for (std::size_t i = 0; i < notes.size(); ++i)
    out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" font-size=\"11\" fill=\"#a00\">{}</text>\n", x0,
                       plot_h + 4 + 18.0 * static_cast<double>(i), escape(notes[i]));
  out << "</svg>\n";
}

}  // namespace mtled::svg
