// What a forward run predicts at each measured datum, read back from its folder: the needle force at a measured
// depth (needle.csv, linear between its equilibrium rows), a constrained set's reaction at a measured displacement
// (reactions.csv's relaxed states, the k-th of N at k/N of the prescribed displacement), a marker's displacement at
// its reference position (result.vtu carried to the marker with MLS, as `mtled compare` carries one cloud onto
// another).
#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <stdexcept>

#include "csv_fields.hpp"
#include "mtled/analysis/compare.hpp"
#include "mtled/analysis/fit.hpp"
#include "mtled/analysis/result_file.hpp"

namespace fs = std::filesystem;

namespace mtled::fit {

namespace {

// A CSV file mtled wrote: its rows as fields, keyed by the header's names.
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name, const fs::path& file) const {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw std::runtime_error(fmt::format("{} has no column {}", file.string(), name));
    return static_cast<int>(it - header.begin());
  }
};

Table read_table(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(fmt::format("the run wrote no {}", file.string()));
  Table table;
  std::string line;
  if (std::getline(in, line)) table.header = csv_fields(line);
  while (std::getline(in, line))
    if (!line.empty()) table.rows.push_back(csv_fields(line));
  return table;
}

// A run's curve sorted by x, with (0, 0) in front when it starts past 0 (no depth, no displacement: no force).
std::vector<std::pair<double, double>> from_origin(std::vector<std::pair<double, double>> curve) {
  std::sort(curve.begin(), curve.end());
  if (curve.empty() || curve.front().first > 0.0) curve.insert(curve.begin(), {0.0, 0.0});
  return curve;
}

// Linear interpolation in a curve from from_origin, held at its ends.
double interpolate(const std::vector<std::pair<double, double>>& curve, double x) {
  if (x <= curve.front().first) return curve.front().second;
  if (x >= curve.back().first) return curve.back().second;
  const auto hi = std::upper_bound(curve.begin(), curve.end(), std::make_pair(x, -HUGE_VAL));
  const auto lo = hi - 1;
  const double t = (x - lo->first) / (hi->first - lo->first);
  return lo->second + t * (hi->second - lo->second);
}

std::vector<double> needle_forces(const Experiment& e, const fs::path& folder) {
  const fs::path file = folder / "needle.csv";
  const Table t = read_table(file);
  const int depth = t.column("depth_m", file), force = t.column("force_N", file);
  std::vector<std::pair<double, double>> curve;
  for (const auto& r : t.rows)
    curve.emplace_back(std::stod(r.at(static_cast<std::size_t>(depth))),
                       std::stod(r.at(static_cast<std::size_t>(force))));
  std::vector<double> out;
  curve = from_origin(std::move(curve));
  for (const auto& d : e.data) out.push_back(interpolate(curve, d.abscissa));
  return out;
}

std::vector<double> reaction_forces(const Experiment& e, const fs::path& folder) {
  const fs::path file = folder / "reactions.csv";
  const Table t = read_table(file);
  const int set = t.column("set", file), force = t.column(fmt::format("f{}_N", "xyz"[e.component]), file);
  std::vector<double> forces;
  for (const auto& r : t.rows)
    if (r.at(static_cast<std::size_t>(set)) == e.set_name)
      forces.push_back(std::stod(r.at(static_cast<std::size_t>(force))));
  if (static_cast<int>(forces.size()) != e.relaxed_increments)
    throw std::runtime_error(fmt::format("{} has {} rows of set {}, expected one per relaxed increment ({})",
                                         file.string(), forces.size(), e.set_name, e.relaxed_increments));
  std::vector<std::pair<double, double>> curve;
  for (std::size_t k = 0; k < forces.size(); ++k)
    curve.emplace_back(e.displacement_full * static_cast<double>(k + 1) / static_cast<double>(forces.size()),
                       forces[k]);
  // Interpolate on |displacement|: the curve runs from 0 toward the prescribed displacement, of either sign.
  const double sign = e.displacement_full < 0.0 ? -1.0 : 1.0;
  for (auto& [x, y] : curve) x *= sign;
  std::vector<double> out;
  curve = from_origin(std::move(curve));
  for (const auto& d : e.data) out.push_back(interpolate(curve, sign * d.abscissa));
  return out;
}

std::vector<double> marker_displacements(const Experiment& e, const fs::path& folder, PluginCatalog& catalog) {
  const ResultField field = read_result_vtu(result_file_of(folder));
  std::vector<Vec3> markers;
  for (std::size_t i = 0; i < e.data.size(); i += 3) markers.push_back(e.data[i].position);
  const std::vector<Vec3> u = interpolate_displacements(field.points, field.displacement, markers, catalog);
  std::vector<double> out;
  for (const auto& d : e.data) out.push_back(u[static_cast<std::size_t>(&d - e.data.data()) / 3][d.component]);
  return out;
}

}  // namespace

std::vector<double> predictions(const Experiment& e, const fs::path& folder, PluginCatalog& catalog) {
  switch (e.quantity) {
    case Quantity::needle_force:
      return needle_forces(e, folder);
    case Quantity::reaction_force:
      return reaction_forces(e, folder);
    case Quantity::markers:
      return marker_displacements(e, folder, catalog);
  }
  return {};
}

}  // namespace mtled::fit
