// mtled study end to end on the small cube: study.csv's rows and columns, the Pareto marking (a run
// dominated in both time and error is off the front), a failing run recorded rather than fatal, the SVG
// plot, the nrmse metric against a reference run, and a bad study file (exit 2, nothing run).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "test_support.hpp"
#include "xml_check.hpp"

namespace fs = std::filesystem;

namespace mtled::test {
namespace {

const fs::path kSmallCube = source_dir() / "tests/scenes/data/small_cube.json";
// The exact top force of the small cube (neo-Hookean, mu = 1000 Pa, D = 4.02684e-5 1/Pa, stretch 0.9, free
// sides; the homogeneous solution as in verification_test.cpp) over its 1e-4 m^2 top face.
constexpr double kExactTopForce = -0.0332529510;

void expect_contains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "expected \"" << part << "\" in:\n" << text;
}

std::size_t column(const std::vector<std::string>& header, const std::string& name) {
  const auto it = std::find(header.begin(), header.end(), name);
  EXPECT_NE(it, header.end()) << "no column " << name;
  return static_cast<std::size_t>(it - header.begin());
}

// One row of study.csv: what the checks below read.
struct StudyRow {
  std::string status, exit_code, pareto;
  double time = NAN, error = NAN;
};

// study.csv's rows by label, after checking the columns every study writes.
std::map<std::string, StudyRow> read_study_rows(const fs::path& csv) {
  const auto rows = read_csv(csv);
  EXPECT_EQ(rows.size(), 5u) << read_text(csv);
  std::map<std::string, StudyRow> entries;
  if (rows.empty()) return entries;
  const auto& header = rows[0];
  for (const auto& row : rows) EXPECT_EQ(row.size(), header.size());
  for (const char* name :
       {"label", "/discretisation/consistent_integration", "/integrator/load_steps", "/integrator/tolerance",
        "/integrator/time_step_factor", "status", "exit_code", "nodes", "steps", "setup_time_s", "solve_time_s",
        "wall_time_s", "peak_rss_mb", "value", "error", "pareto"})
    column(header, name);
  for (std::size_t r = 1; r < rows.size(); ++r) {
    const auto& row = rows[r];
    StudyRow e{row[column(header, "status")], row[column(header, "exit_code")], row[column(header, "pareto")]};
    if (!row[column(header, "wall_time_s")].empty()) e.time = std::stod(row[column(header, "wall_time_s")]);
    if (!row[column(header, "error")].empty()) e.error = std::stod(row[column(header, "error")]);
    entries[row[0]] = e;
  }
  return entries;
}

// The marking is the definition: a run is on the front exactly when no other run is as fast and as accurate. Returns
// how many are.
int checked_pareto_front(const std::map<std::string, StudyRow>& entries) {
  int on_front = 0;
  for (const auto& [label, e] : entries) {
    if (e.status != "ok") continue;
    bool dominated = false;
    for (const auto& [other, o] : entries)
      if (other != label && o.status == "ok" && o.time <= e.time && o.error <= e.error &&
          (o.time < e.time || o.error < e.error))
        dominated = true;
    EXPECT_EQ(e.pareto, dominated ? "false" : "true") << label;
    on_front += e.pareto == "true";
  }
  return on_front;
}

TEST(Study, RecordsEveryConfigurationAndMarksTheParetoFront) {
  const fs::path folder = scratch_dir("study-force");
  const json study = {
      {"description", "small cube against the exact top force"},
      {"scene", kSmallCube.string()},
      {"threads", 1},
      {"metric", "force_error"},
      {"reference", {{"exact_force", {{"set", "top"}, {"component", "z"}, {"value", kExactTopForce}}}}},
      {"configurations",
       {{{"label", "fast"}, {"set", json::object()}},
        // Plain quadrature (percent-level error) relaxed to a tight tolerance over many load steps: slower and
        // less accurate than "fast", so dominated.
        {{"label", "slow_and_worse"},
         {"set",
          {{"/discretisation/consistent_integration", false},
           {"/integrator/load_steps", 3000},
           {"/integrator/tolerance", 1e-8}}}},
        {{"label", "unstable"}, {"set", {{"/integrator/time_step_factor", 8.0}, {"/monitors/stable_step", "stop"}}}}}},
      {"sweep", {{"/integrator/tolerance", {1e-7}}}}};
  write_text(folder / "study.json", study.dump(2));
  const fs::path out = folder / "out";
  const auto result = run_mtled({"study", (folder / "study.json").string(), "-o", out.string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  for (const char* part : {"[1/4] fast", "[2/4] slow_and_worse", "[3/4] unstable", "[4/4] tolerance=1e-07"})
    expect_contains(result.output, part);

  const std::map<std::string, StudyRow> entries = read_study_rows(out / "study.csv");
  ASSERT_EQ(entries.size(), 4u);
  EXPECT_EQ(entries.at("fast").status, "ok");
  EXPECT_EQ(entries.at("slow_and_worse").status, "ok");
  EXPECT_EQ(entries.at("tolerance=1e-07").status, "ok");
  // A run that goes unstable is a row with its status, not the end of the study.
  EXPECT_EQ(entries.at("unstable").status, "unstable");
  EXPECT_EQ(entries.at("unstable").exit_code, "3");
  EXPECT_TRUE(std::isnan(entries.at("unstable").error));
  EXPECT_EQ(entries.at("unstable").pareto, "false");

  // The accurate runs are close to the exact force; plain quadrature is not.
  EXPECT_LT(entries.at("fast").error, 1e-2);
  EXPECT_LT(entries.at("tolerance=1e-07").error, 1e-3);
  EXPECT_GT(entries.at("slow_and_worse").error, entries.at("fast").error);
  EXPECT_GT(entries.at("slow_and_worse").time, entries.at("fast").time);
  EXPECT_EQ(entries.at("slow_and_worse").pareto, "false");
  const int on_front = checked_pareto_front(entries);
  EXPECT_GE(on_front, 1);

  const json report = read_json(out / "study.json");
  EXPECT_EQ(report["metric"]["type"], "force_error");
  EXPECT_EQ(report["metric"]["summary_pointer"], "/final_reactions_N/top/2");
  EXPECT_DOUBLE_EQ(report["reference"]["value"].get<double>(), kExactTopForce);
  EXPECT_EQ(report["configurations"].size(), 4u);
  EXPECT_EQ(report["pareto_front"].size(), static_cast<std::size_t>(on_front));
  for (const auto& c : report["configurations"])
    EXPECT_TRUE(fs::exists(fs::path(c["folder"].get<std::string>()) / "summary.json")) << c["label"];

  const std::string svg = read_text(out / "error_vs_time.svg");
  EXPECT_EQ(xml_problem(svg), "");
  for (const char* part : {"Pareto front", "wall time of the run (s)", "relative error of the top reaction force (z)",
                           "fast", "slow_and_worse", "not plotted: unstable (unstable"})
    expect_contains(svg, part);
  // The front is drawn as a staircase when it has two points or more.
  EXPECT_EQ(svg.find("id=\"pareto-front\"") != std::string::npos, on_front >= 2);
}

// The nrmse metric against a reference configuration run by the study (a denser cloud), with --reuse
// keeping earlier runs.
TEST(Study, NrmseAgainstAReferenceRun) {
  const fs::path folder = scratch_dir("study-nrmse");
  const json study = {{"scene", kSmallCube.string()},
                      {"threads", 1},
                      {"metric", "nrmse"},
                      {"reference", {{"label", "dense"}, {"set", {{"/mesh/target_nodes", 700}}}}},
                      {"sweep", {{"/mesh/target_nodes", {300, 450}}}}};
  write_text(folder / "study.json", study.dump(2));
  const fs::path out = folder / "out";
  auto result = run_mtled({"study", (folder / "study.json").string(), "-o", out.string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto rows = read_csv(out / "study.csv");
  ASSERT_EQ(rows.size(), 3u);
  const auto& header = rows[0];
  for (std::size_t r = 1; r < 3; ++r) {
    EXPECT_EQ(rows[r][column(header, "status")], "ok");
    const double error = std::stod(rows[r][column(header, "error")]);
    double largest = 0.0;
    for (const char* k : {"nrmse_x", "nrmse_y", "nrmse_z"}) largest = std::max(largest, std::stod(rows[r][column(header, k)]));
    EXPECT_DOUBLE_EQ(error, largest);
    EXPECT_GT(error, 0.0);
    EXPECT_LT(error, 0.05);  // coarser clouds of the same problem agree to a few percent
  }
  EXPECT_TRUE(fs::exists(out / "runs" / "dense" / "result.vtu"));
  EXPECT_TRUE(fs::exists(out / "runs" / "target_nodes=300" / "compare.json"));
  EXPECT_EQ(xml_problem(read_text(out / "runs" / "target_nodes=300" / "histograms.svg")), "");
  const json report = read_json(out / "study.json");
  EXPECT_EQ(report["reference"]["label"], "dense");
  EXPECT_EQ(report["reference"]["status"], "ok");

  result = run_mtled({"study", (folder / "study.json").string(), "-o", out.string(), "--reuse"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  expect_contains(result.output, "target_nodes=450: reused");
  EXPECT_TRUE(read_json(out / "study.json")["configurations"][0]["reused"].get<bool>());
}

// The columns of study.csv that do not depend on when or where a run ran (times, memory and the Pareto marking do).
std::vector<std::vector<std::string>> measured_columns(const fs::path& csv) {
  const auto rows = read_csv(csv);
  std::vector<std::vector<std::string>> out;
  for (const auto& row : rows) {
    std::vector<std::string> kept;
    for (const char* name : {"label", "status", "exit_code", "nodes", "steps", "error", "nrmse_x", "nrmse_y", "nrmse_z"})
      kept.push_back(row[column(rows[0], name)]);
    out.push_back(kept);
  }
  return out;
}

// --job-list writes the runs as command lines (a batch scheduler's jobs); run by hand here, then --gather reports
// them exactly as the study run in one go does.
TEST(Study, AJobListRunLineByLineThenGatheredGivesTheSameReport) {
  const fs::path folder = scratch_dir("study-jobs");
  const json study = {{"scene", kSmallCube.string()},
                      {"threads", 1},
                      {"metric", "nrmse"},
                      {"reference", {{"label", "dense"}, {"set", {{"/mesh/target_nodes", 500}}}}},
                      {"sweep", {{"/mesh/target_nodes", {250, 350}}}}};
  write_text(folder / "study.json", study.dump(2));
  const fs::path direct = folder / "direct", jobs = folder / "jobs";
  ASSERT_EQ(run_mtled({"study", (folder / "study.json").string(), "-o", direct.string()}).exit_code, 0);

  const auto listed = run_mtled({"study", (folder / "study.json").string(), "-o", jobs.string(), "--job-list",
                                 (folder / "jobs.txt").string()});
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_FALSE(fs::exists(jobs / "runs" / "dense" / "summary.json")) << "a job list runs nothing";
  std::istringstream lines(read_text(folder / "jobs.txt"));
  std::string line;
  int count = 0;
  while (std::getline(lines, line)) {
    ++count;
    EXPECT_EQ(std::system(line.c_str()), 0) << line;  // sh -c, as a scheduler runs it
  }
  EXPECT_EQ(count, 3);  // the reference and the two sweep points
  const auto gathered = run_mtled({"study", (folder / "study.json").string(), "-o", jobs.string(), "--gather"});
  ASSERT_EQ(gathered.exit_code, 0) << gathered.output;
  EXPECT_EQ(measured_columns(jobs / "study.csv"), measured_columns(direct / "study.csv"));
}

// A configuration's own reference_value (a material sweep, each with its exact force) replaces the study's.
// The small cube with mu doubled has exactly twice the force (the energy scales with mu at fixed mu D).
TEST(Study, AConfigurationsOwnReferenceValueIsUsed) {
  const fs::path folder = scratch_dir("study-own-reference");
  const json study = {
      {"scene", kSmallCube.string()},
      {"threads", 1},
      {"metric", {{"type", "force_error"}, {"set", "top"}, {"component", "z"}}},
      {"reference", {{"value", kExactTopForce}}},
      {"configurations",
       {{{"label", "baseline"}, {"set", json::object()}},
        {{"label", "mu_doubled"},
         {"set", {{"/materials/0/mu", 2000}, {"/materials/0/D", 4.02684e-5 / 2}}},
         {"reference_value", 2 * kExactTopForce}}}}};
  write_text(folder / "study.json", study.dump(2));
  const fs::path out = folder / "out";
  const auto result = run_mtled({"study", (folder / "study.json").string(), "-o", out.string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto rows = read_csv(out / "study.csv");
  ASSERT_EQ(rows.size(), 3u);
  const auto& header = rows[0];
  EXPECT_DOUBLE_EQ(std::stod(rows[1][column(header, "reference_value")]), kExactTopForce);
  EXPECT_DOUBLE_EQ(std::stod(rows[2][column(header, "reference_value")]), 2 * kExactTopForce);
  // Both within the relaxation tolerance of their own exact force (against the study's value the doubled
  // run would be 100% off).
  for (std::size_t r = 1; r < 3; ++r) EXPECT_LT(std::stod(rows[r][column(header, "error")]), 1e-4) << r;
}

TEST(Study, ABadStudyFileExitsTwoAndRunsNothing) {
  const fs::path folder = scratch_dir("study-bad");
  json study = {{"scene", kSmallCube.string()},
                {"metric", "force_error"},
                {"reference", {{"exact_force", {{"set", "top"}, {"component", "z"}, {"value", kExactTopForce}}}}},
                {"configurations", {{{"label", "negative"}, {"set", {{"/materials/0/mu", -5}}}}}}};
  write_text(folder / "study.json", study.dump(2));
  auto result = run_mtled({"study", (folder / "study.json").string(), "-o", (folder / "out").string()});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, "/configurations/0 \"negative\"");
  expect_contains(result.output, "/materials/0/mu");
  EXPECT_FALSE(fs::exists(folder / "out"));

  study.erase("reference");
  study["sweeps"] = json::object();
  write_text(folder / "study.json", study.dump(2));
  result = run_mtled({"study", (folder / "study.json").string(), "-o", (folder / "out").string()});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, "unknown key \"sweeps\"");
  expect_contains(result.output, "/reference: required");

  result = run_mtled({"study", (folder / "missing.json").string(), "-o", (folder / "out").string()});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, "missing.json");
}

}  // namespace
}  // namespace mtled::test
