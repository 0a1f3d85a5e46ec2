// A study's runs: each configuration is a child `mtled run` process with its own folder and log, so a run that
// fails (exit 3, a crash, a timeout) is recorded with its status and the study goes on.
#include <fmt/format.h>

#include <chrono>

#include "mtled/analysis/child_run.hpp"
#include "mtled/analysis/study.hpp"
#include "mtled/plugin_catalog.hpp"
#include "study_support.hpp"

namespace fs = std::filesystem;

namespace mtled::study {

namespace {

void fill(Row& row, const json& summary) {
  row.summary = summary;
  row.status = summary.is_object() ? summary.value("status", "") : "";
  row.setup_s = number_or_nan(summary, "setup_time_s");
  row.solve_s = number_or_nan(summary, "solve_time_s");
  row.wall_s = number_or_nan(summary, "wall_time_s");
  row.peak_mb = number_or_nan(summary, "peak_rss_mb");
  if (summary.is_object()) {
    row.steps = summary.value("steps", -1L);
    row.nodes = summary.value("nodes", -1L);
    row.integration_points = summary.value("integration_points", -1L);
  }
}


// The row's status and message from how the child ended and what its summary says.
void explain_failure(Row& row, const RunOutcome& outcome, double timeout_s, const fs::path& folder) {
  const json& summary = row.summary;
  if (outcome.timed_out) {
    row.status = "timeout";
    row.message = fmt::format("stopped after the study's timeout_s = {:g} s", timeout_s);
  } else if (outcome.signal) {
    row.status = "crashed";
    row.message = fmt::format("killed by signal {}", outcome.signal);
  } else if (row.status.empty() || row.status == "running" || (row.status == "ok" && outcome.exit_code != 0)) {
    row.status = "failed";
  }
  if (row.status != "ok" && row.message.empty()) {
    if (summary.contains("diagnostic")) {
      const json& d = summary["diagnostic"];
      row.message = d.value("detail", "");
      row.note = fmt::format("{} at step {}", d.value("what", "?"), d.value("step", 0L));
    } else if (summary.contains("error") && summary["error"].is_string()) {
      row.message = summary["error"].get<std::string>();
    } else {
      row.message = fmt::format("exit code {}; see {}", row.exit_code, (folder / "mtled.log").string());
    }
  }
  if (row.note.empty()) row.note = row.message.size() > 80 ? row.message.substr(0, 77) + "..." : row.message;
}

}  // namespace

Runner::Runner(const Study& study, const Settings& settings, const fs::path& output)
    : study_(study),
      settings_(settings),
      runs_(output / "runs"),
      executable_(mtled_program("mtled")),
      threads_(settings.threads > 0 ? settings.threads : study.threads) {}

Row Runner::reused(const Configuration& c, const std::string& counter) const {
  Row row;
  row.configuration = &c;
  const fs::path folder = runs_ / c.folder;
  const json summary = read_json_file(folder / "summary.json");
  if (summary.is_object() && summary.value("status", "") == "ok" &&
      summary.value("scene", "") == fs::absolute(study_.scene).string() &&
      summary.value("overrides", json()) == json(c.overrides) && fs::exists(folder / "result.vtu")) {
    row.reused = true;
    row.exit_code = 0;
    fill(row, summary);
    if (!counter.empty()) fmt::print(stderr, "study {} {}: reused the earlier run in {}\n", counter, c.label, folder.string());
  }
  return row;
}

std::vector<std::string> Runner::arguments(const Configuration& c) const {
  std::vector<std::string> arguments{"run", fs::absolute(study_.scene).string(), "-o", (runs_ / c.folder).string(),
                                     "--no-progress", "--log-level", settings_.log_level};
  for (const auto& o : c.overrides) arguments.insert(arguments.end(), {"--set", o});
  if (threads_ > 0) arguments.insert(arguments.end(), {"--threads", std::to_string(threads_)});
  for (const auto& p : settings_.plugin_paths) arguments.insert(arguments.end(), {"--plugin-path", fs::absolute(p).string()});
  return arguments;
}

Row Runner::run(const Configuration& c, const std::string& counter) {
  return record(c, settings_.gather ? outcome_from_folder(c) : execute(c, counter));
}

RunOutcome Runner::execute(const Configuration& c, const std::string& counter) {
  if (settings_.reuse && reused(c, counter).reused) return RunOutcome{.reused = true, .exit_code = 0};
  const fs::path folder = runs_ / c.folder;
  std::error_code ec;
  fs::remove_all(folder, ec);
  fs::create_directories(folder);
  fmt::print(stderr, "study {} {}: running\n", counter, c.label);
  return run_child(executable_, arguments(c), folder / "mtled.log", study_.timeout_s);
}

Row Runner::record(const Configuration& c, const RunOutcome& outcome) const {
  if (outcome.reused) return reused(c, "");
  const fs::path folder = runs_ / c.folder;
  Row row;
  row.configuration = &c;
  row.exit_code = outcome.signal ? 128 + outcome.signal : outcome.exit_code;
  const json summary = read_json_file(folder / "summary.json");
  fill(row, summary);
  if (std::isnan(row.wall_s)) row.wall_s = outcome.elapsed_s;
  if (std::isnan(row.peak_mb)) row.peak_mb = outcome.max_rss_mb;
  explain_failure(row, outcome, study_.timeout_s, folder);
  return row;
}

std::string Runner::command_line(const Configuration& c) const {
  // Single quotes around every word (a quote inside one closes, escapes and reopens it).
  const auto quote = [](const std::string& word) {
    std::string out = "'";
    for (const char ch : word) out += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    return out + "'";
  };
  const fs::path folder = runs_ / c.folder;
  std::string line = "mkdir -p " + quote(folder.string()) + " && " + quote(executable_.string());
  for (const auto& a : arguments(c)) line += " " + quote(a);
  return line + " > " + quote((folder / "mtled.log").string()) + " 2>&1";
}

RunOutcome Runner::outcome_from_folder(const Configuration& c) const {
  const json summary = read_json_file(runs_ / c.folder / "summary.json");
  const std::string status = summary.is_object() ? summary.value("status", "") : "";
  RunOutcome outcome;
  outcome.exit_code = status == "ok" ? 0 : status == "unstable" ? 3 : status == "invalid_input" ? 2 : 1;
  return outcome;
}

}  // namespace mtled::study
