// A study's report: study.csv (one row per configuration), error_vs_time.svg (log-log, the Pareto front
// joined), study.json (the same with the reference and every failure's message), and the table on the terminal.
#include <fmt/format.h>

#include <algorithm>

#include "mtled/analysis/compare.hpp"
#include "mtled/analysis/study.hpp"
#include "mtled/analysis/svg.hpp"
#include "study_support.hpp"

namespace fs = std::filesystem;

namespace mtled::study {

namespace {

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}



void write_csv(const OutputFolder& out, const Study& study, const std::vector<Row>& rows) {
  const bool nrmse = study.metric.kind == MetricKind::nrmse;
  std::vector<std::string> header{"label"};
  header.insert(header.end(), study.varied.begin(), study.varied.end());
  for (const char* h : {"status", "exit_code", "nodes", "integration_points", "steps", "setup_time_s", "solve_time_s",
                        "wall_time_s", "peak_rss_mb"})
    header.emplace_back(h);
  if (nrmse) header.insert(header.end(), {"nrmse_x", "nrmse_y", "nrmse_z"});
  else header.insert(header.end(), {"value", "reference_value"});
  header.insert(header.end(), {"error", "pareto"});
  auto count = [](long v) { return v >= 0 ? std::to_string(v) : std::string(); };
  out.write_file("study.csv", [&](std::ostream& o) {
    for (std::size_t i = 0; i < header.size(); ++i) o << (i ? "," : "") << csv_field(header[i]);
    o << "\n";
    for (const auto& r : rows) {
      std::vector<std::string> f{r.configuration->label};
      for (const auto& p : study.varied) f.push_back(value_text(r.configuration->settings[p]));
      f.insert(f.end(), {r.status, std::to_string(r.exit_code), count(r.nodes), count(r.integration_points), count(r.steps),
                         number_text(r.setup_s), number_text(r.solve_s), number_text(r.wall_s), number_text(r.peak_mb)});
      if (nrmse)
        for (int k = 0; k < 3; ++k) f.push_back(number_text(r.nrmse[k], "{:.6e}"));
      else
        f.insert(f.end(), {number_text(r.value, "{:.9g}"), number_text(r.reference, "{:.9g}")});
      f.insert(f.end(), {number_text(r.error, "{:.6e}"), r.pareto ? "true" : "false"});
      for (std::size_t i = 0; i < f.size(); ++i) o << (i ? "," : "") << csv_field(f[i]);
      o << "\n";
    }
  });

}

void write_plot(const OutputFolder& out, const Study& study, const std::vector<Row>& rows) {
  std::vector<svg::PlotPoint> points;
  std::vector<std::string> notes;
  for (const auto& r : rows) {
    if (r.status == "ok" && std::isfinite(r.error))
      points.push_back({r.configuration->label, r.wall_s, r.error, r.pareto});
    else
      notes.push_back(fmt::format("not plotted: {} ({}{})", r.configuration->label, r.status,
                                  r.note.empty() ? "" : ": " + r.note));
  }
  const std::string title = study.description.empty() ? fmt::format("Error against wall time: {}", study.file.filename().string())
                                                      : study.description;
  out.write_file("error_vs_time.svg", [&](std::ostream& o) {
    svg::write_loglog_plot(o, points, title, "wall time of the run (s)", study.metric.describe, notes);
  });

}

json configuration_json(const Row& r, const OutputFolder& out, bool nrmse) {
  json item = {{"label", r.configuration->label},
               {"folder", (out.path() / "runs" / r.configuration->folder).string()},
               {"set", r.configuration->set},
               {"settings", r.configuration->settings},
               {"status", r.status},
               {"exit_code", r.exit_code},
               {"reused", r.reused},
               {"nodes", r.nodes >= 0 ? json(r.nodes) : json(nullptr)},
               {"integration_points", r.integration_points >= 0 ? json(r.integration_points) : json(nullptr)},
               {"steps", r.steps >= 0 ? json(r.steps) : json(nullptr)},
               {"setup_time_s", number_json(r.setup_s)},
               {"solve_time_s", number_json(r.solve_s)},
               {"wall_time_s", number_json(r.wall_s)},
               {"peak_rss_mb", number_json(r.peak_mb)},
               {"error", number_json(r.error)},
               {"pareto", r.pareto}};
  if (nrmse) {
    item["nrmse"] = {{"ux", number_json(r.nrmse[0])}, {"uy", number_json(r.nrmse[1])}, {"uz", number_json(r.nrmse[2])}};
  } else {
    item["value"] = number_json(r.value);
    item["reference_value"] = number_json(r.reference);
  }
  if (!r.message.empty()) item["message"] = r.message;
  return item;
}

void write_json(const OutputFolder& out, const Study& study, const ReferenceResult& reference, const std::vector<Row>& rows,
                int threads, double study_seconds) {
  const bool nrmse = study.metric.kind == MetricKind::nrmse;
  json configurations = json::array(), front = json::array();
  std::vector<const Row*> by_time;
  for (const auto& r : rows) {
    json item = configuration_json(r, out, nrmse);
    configurations.push_back(std::move(item));
    if (r.pareto) by_time.push_back(&r);
  }
  std::sort(by_time.begin(), by_time.end(), [](const Row* a, const Row* b) { return a->wall_s < b->wall_s; });
  for (const Row* r : by_time) front.push_back(r->configuration->label);
  json metric = {{"type", study.metric.name}, {"description", study.metric.describe}};
  if (!study.metric.pointer.empty()) metric["summary_pointer"] = study.metric.pointer;
  if (nrmse) {
    metric["component"] = study.metric.component < 0 ? "max" : kAxes[study.metric.component];
    metric["definition"] = kNrmseDefinition;
  } else {
    metric["definition"] = "|value - reference| / |reference| (|value - reference| when the reference is 0)";
  }
  const json report = {{"study", study.file.string()},
                       {"scene", study.scene.string()},
                       {"description", study.description},
                       {"metric", metric},
                       {"reference", reference.record},
                       {"threads", threads},
                       {"varied", study.varied},
                       {"configurations", configurations},
                       {"pareto_front", front},
                       {"study_time_s", study_seconds},
                       {"files", {{"table", "study.csv"}, {"plot", "error_vs_time.svg"}, {"runs", "runs"}}}};
  out.write_file("study.json", [&](std::ostream& o) { o << report.dump(2) << "\n"; });
}

}  // namespace

void write_reports(const OutputFolder& out, const Study& study, const ReferenceResult& reference,
                   const std::vector<Row>& rows, int threads, double study_seconds) {
  write_csv(out, study, rows);
  write_plot(out, study, rows);
  write_json(out, study, reference, rows, threads, study_seconds);
}

void print_table(std::ostream& out, const Study& study, const std::vector<Row>& rows, const fs::path& folder,
                 double study_seconds) {
  std::size_t width = 13;
  for (const auto& r : rows) width = std::max(width, r.configuration->label.size());
  out << fmt::format("{:<{}} {:>13} {:>10} {:>10} {:>13} {:>7}\n", "configuration", width, "status", "wall (s)",
                           "memory MB", study.metric.name, "pareto");
  for (const auto& r : rows)
    out << fmt::format("{:<{}} {:>13} {:>10} {:>10} {:>13} {:>7}\n", r.configuration->label, width, r.status,
                             number_text(r.wall_s, "{:.3g}"), number_text(r.peak_mb, "{:.4g}"),
                             number_text(r.error, "{:.3e}"), r.pareto ? "*" : "");
  out << fmt::format("study: {} configurations in {:.3g} s; {}, {}, {} in {}\n", rows.size(), study_seconds,
                           "study.csv", "study.json", "error_vs_time.svg", folder.string());
}

}  // namespace mtled::study
