#include "mtled/analysis/svg.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>

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

// Advance widths of the printable ASCII characters (space to '~') in ems, of DejaVu Sans as librsvg draws it
// (measured): the widest of the fonts the figures name or fall back to, so text laid out with these widths
// fits in Helvetica, Arial or Liberation Sans too.
constexpr double kWidths[95] = {
    0.32, 0.41, 0.46, 0.84, 0.64, 0.96, 0.78, 0.28, 0.40, 0.39, 0.50, 0.84,
    0.32, 0.37, 0.32, 0.34, 0.64, 0.64, 0.64, 0.64, 0.64, 0.64, 0.64, 0.64,
    0.64, 0.64, 0.34, 0.34, 0.84, 0.84, 0.84, 0.54, 1.00, 0.72, 0.69, 0.70,
    0.77, 0.64, 0.58, 0.78, 0.76, 0.30, 0.30, 0.66, 0.56, 0.87, 0.75, 0.79,
    0.61, 0.79, 0.70, 0.64, 0.60, 0.74, 0.69, 0.99, 0.69, 0.62, 0.69, 0.39,
    0.34, 0.39, 0.84, 0.50, 0.50, 0.62, 0.64, 0.56, 0.64, 0.62, 0.36, 0.64,
    0.64, 0.28, 0.28, 0.58, 0.28, 0.98, 0.64, 0.62, 0.64, 0.64, 0.40, 0.53,
    0.40, 0.64, 0.60, 0.82, 0.60, 0.60, 0.53, 0.64, 0.34, 0.64, 0.84};

double text_width(std::string_view text, double size) {
  double ems = 0.0;
  for (unsigned char c : text) {
    if (c >= 32 && c < 127) ems += kWidths[c - 32];
    else if ((c & 0xC0) != 0x80) ems += 1.0;  // a non-ASCII character (UTF-8 lead byte): an em
  }
  return ems * size;
}

// The space a line of text takes: from above the capitals to below the descenders.
struct Box {
  double x0, y0, x1, y1;
  bool overlaps(const Box& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  bool inside(const Box& o) const { return x0 >= o.x0 && x1 <= o.x1 && y0 >= o.y0 && y1 <= o.y1; }
};

enum class Anchor { start, middle, end };
const char* anchor_name(Anchor a) { return a == Anchor::start ? "start" : a == Anchor::middle ? "middle" : "end"; }

Box text_box(double x, double baseline, std::string_view text, double size, Anchor anchor) {
  const double w = text_width(text, size);
  const double left = anchor == Anchor::start ? x : anchor == Anchor::middle ? x - w / 2 : x - w;
  return {left, baseline - 0.95 * size, left + w, baseline + 0.3 * size};
}

// `text` in lines no wider than `width` at `size`, broken at spaces (a word wider than the line gets a line
// of its own and is shrunk by the caller's check).
std::vector<std::string> wrap(std::string_view text, double size, double width) {
  std::vector<std::string> lines;
  std::string line;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = std::min(text.find(' ', at), text.size());
    const std::string_view word = text.substr(at, end - at);
    const std::string candidate = line.empty() ? std::string(word) : line + " " + std::string(word);
    if (!line.empty() && text_width(candidate, size) > width) {
      lines.push_back(line);
      line = std::string(word);
    } else {
      line = candidate;
    }
    at = end + 1;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

// Writes `text` wrapped into `width` from the baseline `y` down, at `size` or smaller so that no line is
// wider; returns the baseline after the last line.
double write_wrapped(std::ostream& out, double x, double y, std::string_view text, double size, double width,
                     Anchor anchor, std::string_view attributes = "") {
  std::vector<std::string> lines = wrap(text, size, width);
  double widest = 0.0;
  for (const auto& line : lines) widest = std::max(widest, text_width(line, size));
  if (widest > width) size *= width / widest;
  for (const auto& line : lines) {
    out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"{}\" font-size=\"{:.3g}\"{}{}>{}</text>\n", x, y,
                       anchor_name(anchor), size, attributes.empty() ? "" : " ", attributes, escape(line));
    y += 1.25 * size;
  }
  return y;
}

// How many lines write_wrapped() will use.
std::size_t line_count(std::string_view text, double size, double width) { return wrap(text, size, width).size(); }

// Tick labels along an axis, leaving out those that would touch the last one kept (log axes with many
// ticks, long numbers).
std::vector<bool> labels_that_fit(const std::vector<double>& positions, const std::vector<std::string>& labels,
                                  double size, bool horizontal) {
  std::vector<bool> keep(positions.size(), false);
  double last_end = -1e300;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const double half = horizontal ? text_width(labels[i], size) / 2 + 3 : 0.7 * size;
    if (positions[i] - half >= last_end) {
      keep[i] = true;
      last_end = positions[i] + half;
    }
  }
  return keep;
}

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

namespace {

void write_svg_start(std::ostream& out, double width, double height) {
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out << fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{0}\" height=\"{1}\" "
                     "viewBox=\"0 0 {0} {1}\" {2} font-size=\"12\">\n",
                     width, height, kFont);
  out << fmt::format("<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"white\"/>\n", width, height);
}

struct HistogramCounts {
  double lo = 0.0, hi = 0.0, bin_width = 0.0;
  std::vector<long> counts;
  long total = 0, most = 1;
};

HistogramCounts count_bins(const std::vector<double>& values, int bins) {
  HistogramCounts h;
  for (double v : values)
    if (std::isfinite(v)) {
      h.lo = std::min(h.lo, v);
      h.hi = std::max(h.hi, v);
    }
  if (!(h.hi - h.lo > 0.0)) {  // every difference is 0: a narrow window around it
    h.lo = -1e-9;
    h.hi = 1e-9;
  }
  h.bin_width = (h.hi - h.lo) / bins;
  h.counts.assign(static_cast<std::size_t>(bins), 0);
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    const auto b = std::clamp(static_cast<long>(std::floor((v - h.lo) / h.bin_width)), 0L, static_cast<long>(bins - 1));
    ++h.counts[static_cast<std::size_t>(b)];
    ++h.total;
  }
  h.most = std::max(1L, *std::max_element(h.counts.begin(), h.counts.end()));
  return h;
}

// About four ticks on a linear x axis at y1 over [lo, hi] (sx maps a value to its x), labelled where they fit.
void write_x_ticks(std::ostream& out, double lo, double hi, const std::function<double(double)>& sx, double y1) {
  const auto x_ticks = linear_ticks(lo, hi, 4);
  std::vector<double> positions;
  std::vector<std::string> labels;
  for (double t : x_ticks) {
    positions.push_back(sx(t));
    labels.push_back(number(t));
  }
  const auto keep = labels_that_fit(positions, labels, 10, true);
  for (std::size_t i = 0; i < x_ticks.size(); ++i) {
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\" stroke=\"black\"/>\n",
                       positions[i], y1, y1 + 4);
    if (keep[i])
      out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\" font-size=\"10\">{}</text>\n",
                         positions[i], y1 + 16, labels[i]);
  }
}

// One panel in the box [x0, x1] x [y0, y1] (the plot area; its labels go around it).
void write_histogram_panel(std::ostream& out, const HistogramPanel& panel, int bins, double x0, double x1, double y0,
                           double y1, double title_y, double title_width) {
  const HistogramCounts h = count_bins(panel.values, bins);
  const auto y_ticks = linear_ticks(0.0, static_cast<double>(h.most), 5);
  const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : 1.0;
  const double y_top = std::max(static_cast<double>(h.most), std::ceil(static_cast<double>(h.most) / y_step) * y_step);
  auto sx = [&](double v) { return x0 + (v - h.lo) / (h.hi - h.lo) * (x1 - x0); };
  auto sy = [&](double c) { return y1 - c / y_top * (y1 - y0); };

  write_wrapped(out, (x0 + x1) / 2, title_y, panel.title, 13, title_width, Anchor::middle);
  for (double t : y_ticks) {
    out << fmt::format("<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"#ddd\"/>\n", x0, sy(t), x1,
                       sy(t));
    out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"end\" font-size=\"10\">{}</text>\n", x0 - 5,
                       sy(t) + 3.5, fmt::format("{:g}", t));
  }
  for (int b = 0; b < bins; ++b) {
    const long c = h.counts[static_cast<std::size_t>(b)];
    if (c == 0) continue;
    const double left_edge = sx(h.lo + b * h.bin_width), right_edge = sx(h.lo + (b + 1) * h.bin_width);
    out << fmt::format("<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" fill=\"#4a7ab5\" "
                       "stroke=\"#2a4a75\" stroke-width=\"0.5\"><title>{} to {}: {} nodes</title></rect>\n",
                       left_edge, sy(static_cast<double>(c)), std::max(right_edge - left_edge, 0.5),
                       y1 - sy(static_cast<double>(c)), number(h.lo + b * h.bin_width),
                       number(h.lo + (b + 1) * h.bin_width), c);
  }
  out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\" stroke=\"#c33\" "
                     "stroke-dasharray=\"4 3\"/>\n",
                     sx(0.0), y0, y1);
  out << fmt::format("<path d=\"M {:.2f} {:.2f} V {:.2f} H {:.2f}\" fill=\"none\" stroke=\"black\"/>\n", x0, y0, y1, x1);
  write_x_ticks(out, h.lo, h.hi, sx, y1);
  write_wrapped(out, (x0 + x1) / 2, y1 + 36, panel.x_label, 12, x1 - x0, Anchor::middle);
  out << fmt::format("<text transform=\"translate({:.2f} {:.2f}) rotate(-90)\" text-anchor=\"middle\">number of "
                     "nodes ({} in all)</text>\n",
                     x0 - 44, (y0 + y1) / 2, h.total);
}

// Where a figure of panels side by side puts one panel: its plot area and its title's first line and width.
struct PanelFrame {
  double x0, x1, top, bottom, title_y, title_width;
};

// The figure both panel kinds share: panels 380 wide side by side under a heading and a smaller subheading (wrapped
// to the figure's width), each title wrapped to its panel's; `draw` fills panel p's frame. `left` and `right` are the
// margins inside a panel for its axis labels.
void write_panel_figure(std::ostream& out, const std::vector<std::string>& titles, const std::string& heading,
                        const std::string& subheading, double left, double right,
                        const std::function<void(std::size_t, const PanelFrame&)>& draw) {
  const double panel_w = 380, panel_h = 330, lower = 56;
  const double width = panel_w * static_cast<double>(std::max<std::size_t>(titles.size(), 1));
  const double text_width_max = width - 24, title_width = panel_w - 16;
  std::size_t title_lines = 1;
  for (const auto& title : titles) title_lines = std::max(title_lines, line_count(title, 13, title_width));
  const double heading_end =
      24 + 20.0 * static_cast<double>(line_count(heading, 16, text_width_max) - 1) +
      (subheading.empty() ? 0.0 : 16.0 * static_cast<double>(line_count(subheading, 11, text_width_max)));
  const double title_y = heading_end + 30;  // first line of the panel titles
  const double top = title_y + 16.25 * static_cast<double>(title_lines);  // top of the plot areas
  const double height = top + panel_h - 30;
  write_svg_start(out, width, height);
  double y = write_wrapped(out, width / 2, 24, heading, 16, text_width_max, Anchor::middle);
  if (!subheading.empty())
    write_wrapped(out, width / 2, y - 4, subheading, 11, text_width_max, Anchor::middle, "fill=\"#444\"");
  for (std::size_t p = 0; p < titles.size(); ++p) {
    const double x0 = static_cast<double>(p) * panel_w + left, x1 = (static_cast<double>(p) + 1) * panel_w - right;
    out << fmt::format("<g id=\"panel{}\">\n", p);
    draw(p, PanelFrame{x0, x1, top, height - lower, title_y, title_width});
    out << "</g>\n";
  }
  out << "</svg>\n";
}

}  // namespace

void write_histograms(std::ostream& out, const std::vector<HistogramPanel>& panels, const std::string& heading,
                      const std::string& subheading, int bins) {
  bins = std::max(bins, 1);
  std::vector<std::string> titles;
  for (const auto& panel : panels) titles.push_back(panel.title);
  write_panel_figure(out, titles, heading, subheading, 62, 28, [&](std::size_t p, const PanelFrame& f) {
    write_histogram_panel(out, panels[p], bins, f.x0, f.x1, f.top, f.bottom, f.title_y, f.title_width);
  });
}

namespace {

// A log-log plot's frame: the data's range widened to whole room, and the map to the drawing.
struct LogFrame {
  double x_lo, x_hi, y_lo, y_hi;
  double x0, x1, y0, y1;  // plot area (y1 is the bottom)
  double sx(double v) const { return x0 + std::log10(v / x_lo) / std::log10(x_hi / x_lo) * (x1 - x0); }
  double sy(double v) const { return v > 0.0 ? y1 - std::log10(v / y_lo) / std::log10(y_hi / y_lo) * (y1 - y0) : y1; }
};

bool plottable(const PlotPoint& p) { return p.x > 0.0 && std::isfinite(p.x) && std::isfinite(p.y); }

void fit_ranges(const std::vector<PlotPoint>& points, LogFrame& f) {
  f.x_lo = f.y_lo = std::numeric_limits<double>::infinity();
  f.x_hi = f.y_hi = 0.0;
  bool has_zero = false;
  for (const auto& p : points) {
    if (!plottable(p)) continue;
    f.x_lo = std::min(f.x_lo, p.x);
    f.x_hi = std::max(f.x_hi, p.x);
    if (p.y > 0.0) {
      f.y_lo = std::min(f.y_lo, p.y);
      f.y_hi = std::max(f.y_hi, p.y);
    } else {
      has_zero = true;
    }
  }
  if (!(f.x_hi > 0.0)) f.x_lo = 0.1, f.x_hi = 10.0;
  if (!(f.y_hi > 0.0)) f.y_lo = 1e-6, f.y_hi = 1.0;
  // Half a decade of room around the data, at least one decade in all.
  f.x_lo /= 1.6, f.x_hi *= 1.6, f.y_lo /= has_zero ? 10.0 : 1.6, f.y_hi *= 1.6;
  if (f.x_hi / f.x_lo < 10.0) {
    const double g = std::sqrt(10.0 / (f.x_hi / f.x_lo));
    f.x_lo /= g, f.x_hi *= g;
  }
  if (f.y_hi / f.y_lo < 10.0) {
    const double g = std::sqrt(10.0 / (f.y_hi / f.y_lo));
    f.y_lo /= g, f.y_hi *= g;
  }
}

void write_log_axes(std::ostream& out, const LogFrame& f, const std::string& x_label, const std::string& y_label) {
  out << "<g id=\"axes\">\n";
  const auto x_ticks = log_ticks(f.x_lo, f.x_hi);
  std::vector<double> positions;
  std::vector<std::string> labels;
  for (double t : x_ticks) positions.push_back(f.sx(t)), labels.push_back(fmt::format("{:g}", t));
  auto keep = labels_that_fit(positions, labels, 11, true);
  for (std::size_t i = 0; i < x_ticks.size(); ++i) {
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\" stroke=\"#ddd\"/>\n",
                       positions[i], f.y0, f.y1);
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\" stroke=\"black\"/>\n",
                       positions[i], f.y1, f.y1 + 5);
    if (keep[i])
      out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\" font-size=\"11\">{}</text>\n",
                         positions[i], f.y1 + 18, labels[i]);
  }
  const auto y_ticks = log_ticks(f.y_lo, f.y_hi);  // ascending values: descending positions
  positions.clear(), labels.clear();
  for (auto t = y_ticks.rbegin(); t != y_ticks.rend(); ++t) positions.push_back(f.sy(*t)), labels.push_back(fmt::format("{:g}", *t));
  keep = labels_that_fit(positions, labels, 11, false);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{2:.2f}\" y2=\"{1:.2f}\" stroke=\"#ddd\"/>\n", f.x0,
                       positions[i], f.x1);
    out << fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{2:.2f}\" y2=\"{1:.2f}\" stroke=\"black\"/>\n",
                       f.x0 - 5, positions[i], f.x0);
    if (keep[i])
      out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"end\" font-size=\"11\">{}</text>\n", f.x0 - 8,
                         positions[i] + 4, labels[i]);
  }
  out << fmt::format("<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" fill=\"none\" "
                     "stroke=\"black\"/>\n",
                     f.x0, f.y0, f.x1 - f.x0, f.y1 - f.y0);
  write_wrapped(out, (f.x0 + f.x1) / 2, f.y1 + 42, x_label, 12, f.x1 - f.x0, Anchor::middle);
  // The y label turned a quarter, so its width is the plot's height.
  const double size = std::min(12.0, 12.0 * (f.y1 - f.y0) / std::max(1.0, text_width(y_label, 12)));
  out << fmt::format("<text transform=\"translate({:.2f} {:.2f}) rotate(-90)\" text-anchor=\"middle\" "
                     "font-size=\"{:.3g}\">{}</text>\n",
                     f.x0 - 62, (f.y0 + f.y1) / 2, size, escape(y_label));
  out << "</g>\n";
}

void write_front(std::ostream& out, const std::vector<PlotPoint>& points, const LogFrame& f) {
  std::vector<const PlotPoint*> front;
  for (const auto& p : points)
    if (p.front && plottable(p)) front.push_back(&p);
  std::sort(front.begin(), front.end(), [](const PlotPoint* a, const PlotPoint* b) { return a->x < b->x; });
  if (front.size() < 2) return;
  std::string d = fmt::format("M {:.2f} {:.2f}", f.sx(front[0]->x), f.sy(front[0]->y));
  for (std::size_t i = 1; i < front.size(); ++i) d += fmt::format(" H {:.2f} V {:.2f}", f.sx(front[i]->x), f.sy(front[i]->y));
  out << fmt::format("<path id=\"pareto-front\" d=\"{}\" fill=\"none\" stroke=\"#c33\" stroke-width=\"1.5\" "
                     "stroke-dasharray=\"5 3\"/>\n",
                     d);
}

// The points and their labels. A label goes to the first of six places around its point that stays inside
// the plot and touches no marker and no label placed before; a point with no such place is listed in
// `unlabelled` instead (written under the plot).
void write_points(std::ostream& out, const std::vector<PlotPoint>& points, const LogFrame& f,
                  std::vector<std::string>& unlabelled) {
  const Box area{f.x0 + 2, f.y0 + 2, f.x1 - 2, f.y1 - 2};
  std::vector<Box> taken;
  for (const auto& p : points)
    if (plottable(p)) taken.push_back({f.sx(p.x) - 6.5, f.sy(p.y) - 6.5, f.sx(p.x) + 6.5, f.sy(p.y) + 6.5});
  struct Place {
    double dx, dy;
    Anchor anchor;
  };
  const Place places[] = {{8, -6, Anchor::start},  {8, 14, Anchor::start},  {-8, -6, Anchor::end},
                          {-8, 14, Anchor::end},   {0, -10, Anchor::middle}, {0, 20, Anchor::middle}};
  out << "<g id=\"points\">\n";
  for (const auto& p : points) {
    if (!plottable(p)) continue;
    const double cx = f.sx(p.x), cy = f.sy(p.y);
    out << fmt::format("<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"5\" fill=\"{}\" stroke=\"{}\" stroke-width=\"1.5\" "
                       "class=\"{}\"><title>{}: {:.4g} s, error {:.4g}</title></circle>\n",
                       cx, cy, p.front ? "#c33" : "white", p.front ? "#c33" : "#555", p.front ? "front" : "dominated",
                       escape(p.label), p.x, p.y);
    const std::string label = p.label + (p.y > 0.0 ? "" : " (error 0)");
    bool placed = false;
    for (const auto& place : places) {
      const Box box = text_box(cx + place.dx, cy + place.dy, label, 10, place.anchor);
      if (!box.inside(area) || std::any_of(taken.begin(), taken.end(), [&](const Box& b) { return b.overlaps(box); }))
        continue;
      out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"{}\" font-size=\"10\" fill=\"#333\">{}</text>\n",
                         cx + place.dx, cy + place.dy, anchor_name(place.anchor), escape(label));
      taken.push_back(box);
      placed = true;
      break;
    }
    if (!placed) unlabelled.push_back(fmt::format("{} ({:.3g} s, {:.3g})", label, p.x, p.y));
  }
  out << "</g>\n";
}

void write_legend(std::ostream& out, double lx, double ly) {
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
}

}  // namespace

void write_loglog_plot(std::ostream& out, const std::vector<PlotPoint>& points, const std::string& title,
                       const std::string& x_label, const std::string& y_label, const std::vector<std::string>& notes) {
  const double width = 820, plot_h = 430, left = 90, right = 230, lower = 64;
  const double title_width = width - 24;
  LogFrame f{};
  fit_ranges(points, f);
  f.x0 = left, f.x1 = width - right;
  f.y0 = 26 + 19.0 * static_cast<double>(line_count(title, 15, title_width)), f.y1 = f.y0 + plot_h - lower;
  // The figure is drawn into a buffer first: the labels that found no place add lines under the plot.
  std::ostringstream body;
  write_wrapped(body, width / 2, 26, title, 15, title_width, Anchor::middle);
  write_log_axes(body, f, x_label, y_label);
  write_front(body, points, f);
  std::vector<std::string> unlabelled;
  write_points(body, points, f, unlabelled);
  write_legend(body, f.x1 + 20, f.y0 + 10);
  std::vector<std::string> lines = notes;
  if (!unlabelled.empty()) {
    std::string list = "not labelled in the plot (no room):";
    for (std::size_t i = 0; i < unlabelled.size(); ++i) list += (i ? "; " : " ") + unlabelled[i];
    lines.push_back(list);
  }
  double y = f.y1 + lower + 8;
  for (const auto& line : lines) y = write_wrapped(body, f.x0, y, line, 11, width - f.x0 - 12, Anchor::start,
                                                   "fill=\"#a00\"");
  write_svg_start(out, width, y + 4);
  out << body.str() << "</svg>\n";
}

namespace {

void write_xy_panel(std::ostream& out, const XyPanel& panel, double x0, double x1, double y0, double y1, double title_y,
                    double title_width) {
  std::vector<double> xs = panel.x_points, ys = panel.y_points;
  xs.insert(xs.end(), panel.x_line.begin(), panel.x_line.end());
  ys.insert(ys.end(), panel.y_line.begin(), panel.y_line.end());
  if (xs.empty()) xs = ys = {0.0};
  auto range = [](const std::vector<double>& v) {
    double lo = *std::min_element(v.begin(), v.end()), hi = *std::max_element(v.begin(), v.end());
    if (!(hi > lo)) { lo -= 1.0 + std::abs(lo); hi += 1.0 + std::abs(hi); }
    const double pad = 0.05 * (hi - lo);
    return std::make_pair(lo - pad, hi + pad);
  };
  auto [xlo, xhi] = range(xs);
  auto [ylo, yhi] = range(ys);
  if (panel.identity_line) xlo = ylo = std::min(xlo, ylo), xhi = yhi = std::max(xhi, yhi);
  auto sx = [&](double v) { return x0 + (v - xlo) / (xhi - xlo) * (x1 - x0); };
  auto sy = [&](double v) { return y1 - (v - ylo) / (yhi - ylo) * (y1 - y0); };
  write_wrapped(out, (x0 + x1) / 2, title_y, panel.title, 13, title_width, Anchor::middle);
  for (double t : linear_ticks(ylo, yhi, 5)) {
    out << fmt::format("<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"#ddd\"/>\n", x0, sy(t),
                       x1, sy(t));
    out << fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"end\" font-size=\"10\">{}</text>\n", x0 - 5,
                       sy(t) + 3.5, number(t));
  }
  write_x_ticks(out, xlo, xhi, sx, y1);
  if (panel.identity_line)
    out << fmt::format("<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"#c33\" "
                       "stroke-dasharray=\"4 3\"/>\n", sx(xlo), sy(xlo), sx(xhi), sy(xhi));
  if (!panel.x_line.empty()) {
    out << "<path fill=\"none\" stroke=\"#c33\" stroke-width=\"1.5\" d=\"";
    for (std::size_t i = 0; i < panel.x_line.size(); ++i)
      out << fmt::format("{}{:.2f} {:.2f}", i ? " L " : "M ", sx(panel.x_line[i]), sy(panel.y_line[i]));
    out << "\"/>\n";
  }
  for (std::size_t i = 0; i < panel.x_points.size(); ++i)
    out << fmt::format("<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"2.5\" fill=\"none\" stroke=\"#2a4a75\"/>\n",
                       sx(panel.x_points[i]), sy(panel.y_points[i]));
  out << fmt::format("<path d=\"M {:.2f} {:.2f} V {:.2f} H {:.2f}\" fill=\"none\" stroke=\"black\"/>\n", x0, y0, y1, x1);
  write_wrapped(out, (x0 + x1) / 2, y1 + 36, panel.x_label, 12, x1 - x0, Anchor::middle);
  out << fmt::format("<text transform=\"translate({:.2f} {:.2f}) rotate(-90)\" text-anchor=\"middle\" "
                     "font-size=\"12\">{}</text>\n", x0 - 48, (y0 + y1) / 2, escape(panel.y_label));
}

}  // namespace

void write_xy_panels(std::ostream& out, const std::vector<XyPanel>& panels, const std::string& heading,
                     const std::string& subheading) {
  std::vector<std::string> titles;
  for (const auto& panel : panels) titles.push_back(panel.title);
  write_panel_figure(out, titles, heading, subheading, 66, 24, [&](std::size_t p, const PanelFrame& f) {
    write_xy_panel(out, panels[p], f.x0, f.x1, f.top, f.bottom, f.title_y, f.title_width);
  });
}

}  // namespace mtled::svg
