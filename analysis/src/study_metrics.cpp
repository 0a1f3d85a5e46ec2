// A study's metrics: the reference it measures against, each run's error, and the Pareto front of error
// against run time.
#include <fmt/format.h>

#include <cmath>
#include <memory>

#include "mtled/analysis/compare.hpp"
#include "mtled/analysis/study.hpp"
#include "mtled/errors.hpp"
#include "mtled/plugin_catalog.hpp"
#include "study_support.hpp"

namespace fs = std::filesystem;

namespace mtled::study {

namespace {

// The quantity a force_error / summary_error metric reads from a summary.
double summary_quantity(const json& summary, const std::string& pointer, const std::string& what) {
  const json::json_pointer p(pointer);
  if (!summary.is_object() || !summary.contains(p) || !summary.at(p).is_number())
    throw InputError(what, fmt::format("summary.json has no number at {}", pointer));
  return summary.at(p).get<double>();
}

double relative_error(double value, double reference) {
  return reference != 0.0 ? std::abs(value - reference) / std::abs(reference) : std::abs(value - reference);
}

}  // namespace

ReferenceResult establish_reference(const Study& study, Runner& runner) {
  ReferenceResult reference;
  reference.value = study.reference.value;
  reference.record = {{"kind", study.reference.kind == Reference::Kind::value ? "value"
                               : study.reference.kind == Reference::Kind::run ? "run"
                                                                               : "configuration"}};
  const bool by_value = study.metric.kind != MetricKind::nrmse;
  if (study.reference.kind == Reference::Kind::run) {
    reference.folder = study.reference.run;
    if (by_value)
      reference.value = summary_quantity(read_json_file(reference.folder / "summary.json"), study.metric.pointer,
                                         (reference.folder / "summary.json").string());
  } else if (study.reference.kind == Reference::Kind::configuration) {
    const Configuration& c = study.reference.configuration;
    const Row row = runner.run(c, "[reference]");
    reference.folder = runner.folder(c);
    reference.record["label"] = c.label;
    reference.record["set"] = c.set;
    reference.record["status"] = row.status;
    reference.record["wall_time_s"] = number_json(row.wall_s);
    reference.record["nodes"] = row.nodes;
    fmt::print(stderr, "study [reference] {}: {} in {:.3g} s\n", c.label, row.status, row.wall_s);
    if (row.status != "ok")
      throw std::runtime_error(fmt::format("the reference run \"{}\" did not succeed (status {}): {}; nothing to "
                                           "measure against",
                                           c.label, row.status, row.message));
    if (by_value)
      reference.value = summary_quantity(row.summary, study.metric.pointer, (reference.folder / "summary.json").string());
  }
  if (!reference.folder.empty()) reference.record["run"] = reference.folder.string();
  if (by_value) reference.record["value"] = reference.value;
  return reference;
}

Measure::Measure(const Study& study, const ReferenceResult& reference, const std::vector<fs::path>& plugin_paths)
    : study_(study), reference_(reference) {
  if (study.metric.kind == MetricKind::nrmse)
    catalog_ = std::make_unique<PluginCatalog>(plugin_search_path(plugin_paths, {}));
}

Measure::~Measure() = default;

void Measure::operator()(Row& row, const fs::path& folder) const {
  if (row.status != "ok") return;
  const Configuration& c = *row.configuration;
  try {
    if (study_.metric.kind == MetricKind::nrmse) {
      const Comparison comparison = compare_runs(folder, reference_.folder, *catalog_);
      row.nrmse = comparison.nrmse;
      row.error = study_.metric.component < 0 ? comparison.nrmse.maxCoeff() : comparison.nrmse[study_.metric.component];
      const OutputFolder run_folder(folder);
      run_folder.write_file("compare.json", [&](std::ostream& o) { o << comparison_json(comparison).dump(2) << "\n"; });
      run_folder.write_file("histograms.svg", [&](std::ostream& o) {
        write_comparison_histograms(o, comparison, c.label, reference_.folder.filename().string(), 41);
      });
    } else {
      row.value = summary_quantity(row.summary, study_.metric.pointer, (folder / "summary.json").string());
      row.reference = c.reference_value.value_or(reference_.value);
      row.error = relative_error(row.value, row.reference);
    }
  } catch (const std::exception& e) {
    row.status = "metric_failed";
    row.message = e.what();
    row.note = row.message.size() > 80 ? row.message.substr(0, 77) + "..." : row.message;
  }
}

// A run is on the Pareto front when no other successful run is at least as fast and at least as accurate,
// and strictly better in one of the two.
void mark_pareto(std::vector<Row>& rows) {
  auto usable = [](const Row& r) { return r.status == "ok" && std::isfinite(r.error) && std::isfinite(r.wall_s); };
  for (auto& r : rows) {
    r.pareto = usable(r);
    for (const auto& o : rows) {
      if (!r.pareto) break;
      if (&o == &r || !usable(o)) continue;
      if (o.wall_s <= r.wall_s && o.error <= r.error && (o.wall_s < r.wall_s || o.error < r.error)) r.pareto = false;
    }
  }
}

}  // namespace mtled::study
