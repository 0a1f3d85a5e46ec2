// mtled study: runs a scene under several settings (a list of configurations and/or a cartesian sweep),
// measures each against a reference with a named metric, and reports error against run time: study.csv,
// study.json and error_vs_time.svg (log-log, Pareto front marked). Each run is a child `mtled run` process,
// so a run that fails (exit 3, a crash, a timeout) is recorded with its status and the study goes on.
// The file format is documented in docs/studies.md.
#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <fstream>
#include <iostream>
#include <set>
#include <thread>

#include "commands.hpp"
#include "mtled/analysis/compare.hpp"
#include "mtled/errors.hpp"
#include "mtled/log.hpp"
#include "mtled/output.hpp"
#include "mtled/scene.hpp"
#include "svg.hpp"

namespace fs = std::filesystem;

namespace mtled::app {

namespace {

using Clock = std::chrono::steady_clock;

struct Configuration {
  std::string label;
  std::string folder;             // folder name under runs/
  std::string where;              // its place in the study file, for messages
  json set = json::object();      // JSON pointer -> value: the study's common "set", then its own
  std::vector<std::string> overrides;  // the --set arguments
  json settings = json::object();      // value of every varied pointer in the scene as run ("default" if absent)
  std::optional<double> reference_value;  // its own exact value, for value metrics (a material sweep)
};

enum class MetricKind { nrmse, force_error, summary_error };

struct Metric {
  MetricKind kind = MetricKind::nrmse;
  std::string pointer;   // force_error, summary_error: JSON pointer of the quantity in summary.json
  int component = -1;    // nrmse: -1 for the largest of x, y, z; else 0, 1, 2
  std::string name;      // "nrmse", "force_error", "summary_error"
  std::string describe;  // axis label
};

struct Reference {
  enum class Kind { value, run, configuration } kind = Kind::value;
  double value = 0.0;
  fs::path run;  // Kind::run: the folder; Kind::configuration: the folder it is run into
  Configuration configuration;
};

struct Study {
  fs::path file, scene;
  std::string description;
  std::vector<Configuration> configurations;
  std::vector<std::string> varied;  // pointers set anywhere, in order of first appearance
  Metric metric;
  Reference reference;
  int threads = 0;
  double timeout_s = 0.0;
};

struct Row {
  const Configuration* configuration = nullptr;
  std::string status;
  int exit_code = -1;
  bool reused = false;
  json summary;
  double setup_s = NAN, solve_s = NAN, wall_s = NAN, peak_mb = NAN;
  long steps = -1, nodes = -1, integration_points = -1;
  double value = NAN;            // force_error, summary_error: the quantity
  double reference = NAN;        // ... and the value it is measured against
  Vec3 nrmse = Vec3::Constant(NAN);
  double error = NAN;
  bool pareto = false;
  std::string message;  // why it failed, in full (study.json)
  std::string note;     // the same in a few words (the plot)
};

const char* const kAxes[] = {"x", "y", "z"};

int axis_index(const std::string& name) {
  for (int k = 0; k < 3; ++k)
    if (name == kAxes[k] || name == std::string("u") + kAxes[k]) return k;
  return -1;
}

std::string value_text(const json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

// A folder name from a label: letters, digits and . _ = , + - kept, anything else becomes '-'.
std::string folder_name(const std::string& label) {
  std::string out;
  for (char c : label)
    out += std::isalnum(static_cast<unsigned char>(c)) || std::string("._=,+-").find(c) != std::string::npos ? c : '-';
  if (!out.empty() && out[0] == '.') out[0] = '_';
  return out;
}

std::string last_token(const std::string& pointer) {
  const auto slash = pointer.rfind('/');
  return slash == std::string::npos ? pointer : pointer.substr(slash + 1);
}

// ----------------------------------------------------------------------------------------------------
// Reading the study file.

class StudyReader {
 public:
  explicit StudyReader(const fs::path& file) : file_(file) {}

  Study read() {
    std::ifstream in(file_);
    if (!in) throw InputError(file_.string(), "cannot read the study file");
    json root;
    try {
      root = json::parse(in, nullptr, true, /*ignore_comments=*/true);
    } catch (const json::parse_error& e) {
      throw InputError(file_.string(), fmt::format("not valid JSON: {}", e.what()));
    }
    if (!root.is_object()) throw InputError(file_.string(), "a study is a JSON object (docs/studies.md)");
    static const std::set<std::string> kKeys = {"description", "scene",   "set",     "configurations", "sweep",
                                                "reference",   "metric",  "threads", "timeout_s"};
    for (const auto& [key, value] : root.items())
      if (!kKeys.count(key)) {
        std::vector<std::string> names(kKeys.begin(), kKeys.end());
        const std::string hint = did_you_mean(key, names);
        problem("/" + key, fmt::format("unknown key \"{}\"{}", key, hint.empty() ? "" : "; " + hint));
      }

    Study study;
    study.file = fs::absolute(file_);
    study.description = root.value("description", "");
    if (!root.contains("scene") || !root["scene"].is_string()) {
      problem("/scene", "required: the scene file, relative to the study file's folder");
    } else {
      study.scene = (study.file.parent_path() / root["scene"].get<std::string>()).lexically_normal();
      if (!fs::is_regular_file(study.scene)) problem("/scene", fmt::format("no such scene file: {}", study.scene.string()));
    }
    json common = json::object();
    if (root.contains("set")) common = read_set(root["set"], "/set");
    if (root.contains("threads")) {
      if (!root["threads"].is_number_integer() || root["threads"].get<int>() < 0)
        problem("/threads", "a whole number >= 0");
      else
        study.threads = root["threads"].get<int>();
    }
    if (root.contains("timeout_s")) {
      if (!root["timeout_s"].is_number() || root["timeout_s"].get<double>() <= 0.0)
        problem("/timeout_s", "a number of seconds > 0");
      else
        study.timeout_s = root["timeout_s"].get<double>();
    }

    // Configurations: the listed ones, then the sweep's cartesian product.
    if (root.contains("configurations")) {
      const json& list = root["configurations"];
      if (!list.is_array()) problem("/configurations", "a list of {\"label\": ..., \"set\": {...}}");
      for (std::size_t i = 0; list.is_array() && i < list.size(); ++i) {
        const std::string where = fmt::format("/configurations/{}", i);
        const json& item = list[i];
        if (!item.is_object() || !item.contains("label") || !item["label"].is_string()) {
          problem(where, "needs a \"label\" (string) and a \"set\" object");
          continue;
        }
        for (const auto& [key, value] : item.items())
          if (key != "label" && key != "set" && key != "reference_value")
            problem(where + "/" + key, fmt::format("unknown key \"{}\" (a configuration has \"label\", \"set\" and "
                                                   "optionally \"reference_value\")", key));
        Configuration c;
        if (item.contains("reference_value")) {
          if (!item["reference_value"].is_number())
            problem(where + "/reference_value", "a number: this configuration's exact value of the metric's quantity");
          else
            c.reference_value = item["reference_value"].get<double>();
        }
        c.label = item["label"].get<std::string>();
        c.where = where;
        c.set = common;
        if (item.contains("set")) c.set.update(read_set(item["set"], where + "/set"));
        study.configurations.push_back(std::move(c));
      }
    }
    if (root.contains("sweep")) {
      // The sweep's axes in the file's order (json objects are sorted): the last varies fastest.
      std::ifstream again(file_);
      const auto ordered = nlohmann::ordered_json::parse(again, nullptr, false, true);
      std::vector<std::string> order;
      if (ordered.is_object() && ordered.contains("sweep") && ordered["sweep"].is_object())
        for (const auto& item : ordered["sweep"].items()) order.push_back(item.key());
      read_sweep(root["sweep"], order, common, study.configurations);
    }
    if (study.configurations.empty() && problems_.empty())
      problem("/configurations", "the study has no configurations: give \"configurations\" or \"sweep\"");

    std::set<std::string> labels, folders;
    for (auto& c : study.configurations) {
      c.folder = folder_name(c.label);
      if (c.label.empty()) problem(c.where + "/label", "must not be empty");
      if (!labels.insert(c.label).second) problem(c.where + "/label", fmt::format("\"{}\" is used twice", c.label));
      else if (!folders.insert(c.folder).second)
        problem(c.where + "/label", fmt::format("\"{}\" gives the same folder name as another label", c.label));
    }

    read_metric_and_reference(root, common, study);
    if (study.reference.kind == Reference::Kind::configuration && folders.count(study.reference.configuration.folder))
      problem("/reference/label", fmt::format("\"{}\" is also a configuration's label",
                                              study.reference.configuration.label));

    for (const auto& c : study.configurations)
      for (const auto& [pointer, value] : c.set.items())
        if (std::find(study.varied.begin(), study.varied.end(), pointer) == study.varied.end())
          study.varied.push_back(pointer);
    if (!problems_.empty()) throw InputError(problems_);
    return study;
  }

 private:
  void problem(const std::string& pointer, const std::string& message) {
    problems_.push_back({fmt::format("{}: {}", file_.string(), pointer), message});
  }

  json read_set(const json& set, const std::string& where) {
    if (!set.is_object()) {
      problem(where, "an object of {\"/json/pointer\": value} scene overrides");
      return json::object();
    }
    for (const auto& [pointer, value] : set.items())
      if (pointer.empty() || pointer[0] != '/')
        problem(where, fmt::format("\"{}\" is not a JSON pointer (it starts with /, e.g. \"/mesh/target_nodes\")", pointer));
    return set;
  }

  void read_sweep(const json& sweep, const std::vector<std::string>& order, const json& common,
                  std::vector<Configuration>& out) {
    if (!sweep.is_object() || sweep.empty()) {
      problem("/sweep", "an object of {\"/json/pointer\": [values...]}; every combination is run");
      return;
    }
    std::vector<std::pair<std::string, json>> axes;
    for (const auto& pointer : order) {
      const json& values = sweep.at(pointer);
      if (pointer.empty() || pointer[0] != '/') problem("/sweep", fmt::format("\"{}\" is not a JSON pointer", pointer));
      if (!values.is_array() || values.empty()) {
        problem("/sweep/" + pointer, "a non-empty list of values");
        return;
      }
      axes.emplace_back(pointer, values);
    }
    std::vector<std::size_t> index(axes.size(), 0);
    while (true) {
      Configuration c;
      c.where = "/sweep";
      c.set = common;
      std::string label;
      for (std::size_t a = 0; a < axes.size(); ++a) {
        const json& v = axes[a].second[index[a]];
        c.set[axes[a].first] = v;
        label += fmt::format("{}{}={}", a ? "," : "", last_token(axes[a].first), value_text(v));
      }
      c.label = label;
      out.push_back(std::move(c));
      std::size_t a = axes.size();
      while (a > 0 && ++index[a - 1] == axes[a - 1].second.size()) index[--a] = 0;
      if (a == 0) break;
    }
  }

  void read_metric_and_reference(const json& root, const json& common, Study& study) {
    Metric& m = study.metric;
    Reference& r = study.reference;
    json metric = root.value("metric", json("nrmse"));
    if (metric.is_string()) metric = json{{"type", metric}};
    const json reference = root.value("reference", json());
    // Shorthand: {"exact_force": {"set": "top", "component": "z", "value": -0.06}}.
    if (reference.is_object() && reference.contains("exact_force")) {
      const json& e = reference["exact_force"];
      if (!e.is_object() || !e.contains("value") || !e["value"].is_number()) {
        problem("/reference/exact_force", "needs \"set\", \"component\" and a numeric \"value\" (N)");
        return;
      }
      if (!metric.contains("set")) metric["set"] = e.value("set", "");
      if (!metric.contains("component")) metric["component"] = e.value("component", "");
      if (metric.value("type", "") != "force_error")
        problem("/metric", "\"exact_force\" goes with the metric \"force_error\"");
    }
    if (!metric.is_object() || !metric.contains("type") || !metric["type"].is_string()) {
      problem("/metric", "\"nrmse\", \"force_error\" or \"summary_error\" (or an object with \"type\")");
      return;
    }
    m.name = metric["type"].get<std::string>();
    if (m.name == "nrmse") {
      m.kind = MetricKind::nrmse;
      const std::string component = metric.value("component", "max");
      m.component = component == "max" ? -1 : axis_index(component);
      if (component != "max" && m.component < 0) problem("/metric/component", "\"max\", \"x\", \"y\" or \"z\"");
      m.describe = m.component < 0 ? "NRMSE of the displacement (largest of x, y, z)"
                                   : fmt::format("NRMSE of the displacement u_{}", kAxes[m.component]);
    } else if (m.name == "force_error") {
      m.kind = MetricKind::force_error;
      const std::string set = metric.value("set", "");
      const int k = axis_index(metric.value("component", ""));
      if (set.empty()) problem("/metric/set", "the constrained node set whose reaction force is measured (e.g. \"top\")");
      if (k < 0) problem("/metric/component", "\"x\", \"y\" or \"z\"");
      m.pointer = fmt::format("/final_reactions_N/{}/{}", set, std::max(k, 0));
      m.describe = fmt::format("relative error of the {} reaction force ({})", set, k >= 0 ? kAxes[k] : "?");
    } else if (m.name == "summary_error") {
      m.kind = MetricKind::summary_error;
      m.pointer = metric.value("pointer", "");
      if (m.pointer.empty() || m.pointer[0] != '/')
        problem("/metric/pointer", "the JSON pointer of a number in summary.json, e.g. \"/needle/final_force_N\"");
      m.describe = fmt::format("relative error of {} (summary.json)", m.pointer);
    } else {
      problem("/metric", fmt::format("unknown metric \"{}\": \"nrmse\", \"force_error\" or \"summary_error\"", m.name));
      return;
    }

    if (!reference.is_object()) {
      problem("/reference", "required: {\"value\": number}, {\"run\": folder}, {\"label\": ..., \"set\": {...}} or "
                            "{\"exact_force\": {...}}");
      return;
    }
    if (reference.contains("exact_force")) {
      r.kind = Reference::Kind::value;
      r.value = reference["exact_force"]["value"].get<double>();
    } else if (reference.contains("value")) {
      r.kind = Reference::Kind::value;
      if (!reference["value"].is_number()) problem("/reference/value", "a number");
      else r.value = reference["value"].get<double>();
    } else if (reference.contains("run")) {
      r.kind = Reference::Kind::run;
      if (!reference["run"].is_string()) {
        problem("/reference/run", "the folder of an earlier run, relative to the study file's folder");
      } else {
        r.run = (study.file.parent_path() / reference["run"].get<std::string>()).lexically_normal();
        if (m.kind == MetricKind::nrmse) {
          try {
            result_file_of(r.run);
          } catch (const InputError& e) {
            for (const auto& p : e.problems()) problem("/reference/run", p.format());
          }
        } else if (!fs::exists(r.run / "summary.json")) {
          problem("/reference/run", fmt::format("{} holds no summary.json", r.run.string()));
        }
      }
    } else if (reference.contains("set")) {
      r.kind = Reference::Kind::configuration;
      r.configuration.label = reference.value("label", "reference");
      r.configuration.folder = folder_name(r.configuration.label);
      r.configuration.where = "/reference";
      r.configuration.set = common;
      r.configuration.set.update(read_set(reference["set"], "/reference/set"));
    } else {
      problem("/reference", "one of \"value\", \"run\", \"set\" (with \"label\") or \"exact_force\"");
    }
    if (m.kind == MetricKind::nrmse && r.kind == Reference::Kind::value)
      problem("/reference", "the metric \"nrmse\" compares displacement fields: give a \"run\" or a \"set\" to run");
    for (const auto& c : study.configurations)
      if (c.reference_value && m.kind == MetricKind::nrmse)
        problem(c.where + "/reference_value", "only for the metrics \"force_error\" and \"summary_error\"");
  }

  fs::path file_;
  std::vector<Problem> problems_;
};

// Checks every configuration's scene as `mtled validate` would, before anything runs; fills overrides and
// settings.
void prepare(Study& study, const StudyOptions& options) {
  std::vector<Problem> problems;
  auto check = [&](Configuration& c) {
    c.overrides.clear();
    for (const auto& [pointer, value] : c.set.items()) c.overrides.push_back(pointer + "=" + value.dump());
    try {
      SceneDocument document = read_scene(study.scene, c.overrides);
      for (const auto& pointer : study.varied) {
        const json::json_pointer p(pointer);
        c.settings[pointer] = document.root.contains(p) ? document.root.at(p) : json("default");
      }
      PluginCatalog catalog(plugin_search_path(options.plugin_paths, scene_plugin_paths(document)));
      validate_scene(std::move(document), catalog);
    } catch (const InputError& e) {
      for (const auto& p : e.problems())
        problems.push_back({fmt::format("{}: {} \"{}\": {}", study.file.string(), c.where, c.label, p.where), p.message});
    } catch (const json::exception& e) {
      problems.push_back({fmt::format("{}: {} \"{}\"", study.file.string(), c.where, c.label), e.what()});
    }
  };
  for (auto& c : study.configurations) check(c);
  if (study.reference.kind == Reference::Kind::configuration) check(study.reference.configuration);
  if (!problems.empty()) throw InputError(problems);
}

// ----------------------------------------------------------------------------------------------------
// Running one configuration as a child process.

struct ChildOutcome {
  int exit_code = -1;
  int signal = 0;
  bool timed_out = false;
  double elapsed_s = 0.0;
  double max_rss_mb = 0.0;
};

ChildOutcome run_child(const fs::path& executable, const std::vector<std::string>& arguments, const fs::path& log_file,
                       double timeout_s) {
  std::vector<std::string> args{executable.string()};
  args.insert(args.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string log_path = log_file.string();

  const auto start = Clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(fmt::format("cannot start a run: fork failed ({})", std::strerror(errno)));
  if (pid == 0) {  // the child: only async-signal-safe calls until exec
    const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, STDOUT_FILENO);
      ::dup2(fd, STDERR_FILENO);
      ::close(fd);
    }
    const int null = ::open("/dev/null", O_RDONLY);
    if (null >= 0) ::dup2(null, STDIN_FILENO);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ChildOutcome outcome;
  int status = 0;
  rusage usage{};
  bool terminated = false;
  while (true) {
    const pid_t done = ::wait4(pid, &status, timeout_s > 0.0 ? WNOHANG : 0, &usage);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) throw std::runtime_error(fmt::format("waiting for a run failed ({})", std::strerror(errno)));
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (timeout_s > 0.0 && elapsed > timeout_s && !terminated) {
      ::kill(pid, SIGTERM);  // mtled run writes summary.json with status "interrupted" and exits
      terminated = outcome.timed_out = true;
    }
    if (terminated && elapsed > timeout_s + 30.0) ::kill(pid, SIGKILL);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  outcome.elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
  outcome.max_rss_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
  if (WIFEXITED(status)) outcome.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) outcome.signal = WTERMSIG(status);
  return outcome;
}

json read_json_file(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return json();
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return json();
  }
}

double number_or_nan(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : NAN;
}

class StudyRunner {
 public:
  StudyRunner(const Study& study, const StudyOptions& options, const fs::path& output)
      : study_(study), options_(options), output_(output), runs_(output / "runs") {
    executable_ = fs::read_symlink("/proc/self/exe");
    threads_ = options.threads > 0 ? options.threads : study.threads;
  }

  // Runs one configuration (or reuses its earlier run) and reads its summary.
  Row run(const Configuration& c, const std::string& counter) {
    Row row;
    row.configuration = &c;
    const fs::path folder = runs_ / c.folder;
    const fs::path scene = fs::absolute(study_.scene);
    if (options_.reuse) {
      const json summary = read_json_file(folder / "summary.json");
      if (summary.is_object() && summary.value("status", "") == "ok" && summary.value("scene", "") == scene.string() &&
          summary.value("overrides", json()) == json(c.overrides) && fs::exists(folder / "result.vtu")) {
        row.reused = true;
        row.exit_code = 0;
        fill(row, summary);
        fmt::print(stderr, "study {} {}: reused the earlier run in {}\n", counter, c.label, folder.string());
        return row;
      }
    }
    std::error_code ec;
    fs::remove_all(folder, ec);
    fs::create_directories(folder);
    std::vector<std::string> arguments{"run", scene.string(), "-o", folder.string(), "--no-progress",
                                       "--log-level", options_.log_level};
    for (const auto& o : c.overrides) arguments.insert(arguments.end(), {"--set", o});
    if (threads_ > 0) arguments.insert(arguments.end(), {"--threads", std::to_string(threads_)});
    for (const auto& p : options_.plugin_paths) arguments.insert(arguments.end(), {"--plugin-path", fs::absolute(p).string()});
    fmt::print(stderr, "study {} {}: running\n", counter, c.label);
    const ChildOutcome outcome = run_child(executable_, arguments, folder / "mtled.log", study_.timeout_s);
    row.exit_code = outcome.signal ? 128 + outcome.signal : outcome.exit_code;
    const json summary = read_json_file(folder / "summary.json");
    fill(row, summary);
    if (std::isnan(row.wall_s)) row.wall_s = outcome.elapsed_s;
    if (std::isnan(row.peak_mb)) row.peak_mb = outcome.max_rss_mb;
    if (outcome.timed_out) {
      row.status = "timeout";
      row.message = fmt::format("stopped after the study's timeout_s = {:g} s", study_.timeout_s);
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
    return row;
  }

  fs::path folder(const Configuration& c) const { return runs_ / c.folder; }

 private:
  static void fill(Row& row, const json& summary) {
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

  const Study& study_;
  const StudyOptions& options_;
  fs::path output_, runs_, executable_;
  int threads_ = 0;
};

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

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string number_text(double v, const char* format = "{:.6g}") {
  return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : std::string();
}

json number_json(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

}  // namespace

int study_command(const StudyOptions& options) {
  Study study = StudyReader(options.study).read();
  prepare(study, options);
  const OutputFolder out(options.output);
  fs::create_directories(out.path() / "runs");
  StudyRunner runner(study, options, out.path());
  const auto study_start = Clock::now();

  // The reference first.
  fs::path reference_folder;
  double reference_value = study.reference.value;
  json reference_json = {{"kind", study.reference.kind == Reference::Kind::value ? "value"
                                  : study.reference.kind == Reference::Kind::run ? "run"
                                                                                  : "configuration"}};
  if (study.reference.kind == Reference::Kind::run) {
    reference_folder = study.reference.run;
    if (study.metric.kind != MetricKind::nrmse)
      reference_value = summary_quantity(read_json_file(reference_folder / "summary.json"), study.metric.pointer,
                                         (reference_folder / "summary.json").string());
  } else if (study.reference.kind == Reference::Kind::configuration) {
    const Configuration& c = study.reference.configuration;
    const Row row = runner.run(c, "[reference]");
    reference_folder = runner.folder(c);
    reference_json["label"] = c.label;
    reference_json["set"] = c.set;
    reference_json["status"] = row.status;
    reference_json["wall_time_s"] = number_json(row.wall_s);
    reference_json["nodes"] = row.nodes;
    fmt::print(stderr, "study [reference] {}: {} in {:.3g} s\n", c.label, row.status, row.wall_s);
    if (row.status != "ok")
      throw std::runtime_error(fmt::format("the reference run \"{}\" did not succeed (status {}): {}; nothing to "
                                           "measure against",
                                           c.label, row.status, row.message));
    if (study.metric.kind != MetricKind::nrmse)
      reference_value = summary_quantity(row.summary, study.metric.pointer, (reference_folder / "summary.json").string());
  }
  if (!reference_folder.empty()) reference_json["run"] = reference_folder.string();
  if (study.metric.kind != MetricKind::nrmse) reference_json["value"] = reference_value;

  std::unique_ptr<PluginCatalog> compare_catalog;
  if (study.metric.kind == MetricKind::nrmse)
    compare_catalog = std::make_unique<PluginCatalog>(plugin_search_path(options.plugin_paths, {}));

  std::vector<Row> rows;
  const std::size_t n = study.configurations.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Configuration& c = study.configurations[i];
    const std::string counter = fmt::format("[{}/{}]", i + 1, n);
    Row row = runner.run(c, counter);
    if (row.status == "ok") {
      try {
        if (study.metric.kind == MetricKind::nrmse) {
          const Comparison comparison = compare_runs(runner.folder(c), reference_folder, *compare_catalog);
          row.nrmse = comparison.nrmse;
          row.error = study.metric.component < 0 ? comparison.nrmse.maxCoeff() : comparison.nrmse[study.metric.component];
          const OutputFolder run_folder(runner.folder(c));
          run_folder.write_file("compare.json", [&](std::ostream& o) { o << comparison_json(comparison).dump(2) << "\n"; });
          run_folder.write_file("histograms.svg", [&](std::ostream& o) {
            write_comparison_histograms(o, comparison, c.label, reference_folder.filename().string(), 41);
          });
        } else {
          row.value = summary_quantity(row.summary, study.metric.pointer, (runner.folder(c) / "summary.json").string());
          row.reference = c.reference_value.value_or(reference_value);
          row.error = relative_error(row.value, row.reference);
        }
      } catch (const std::exception& e) {
        row.status = "metric_failed";
        row.message = e.what();
        row.note = row.message.size() > 80 ? row.message.substr(0, 77) + "..." : row.message;
      }
    }
    rows.push_back(std::move(row));
    const Row& r = rows.back();
    if (r.status == "ok")
      fmt::print(stderr, "study {} {}: ok, wall {:.3g} s, {} {:.4g}\n", counter, c.label, r.wall_s, study.metric.name,
                 r.error);
    else
      fmt::print(stderr, "study {} {}: {} (exit {}){}\n", counter, c.label, r.status, r.exit_code,
                 r.message.empty() ? "" : ": " + r.message);
  }
  mark_pareto(rows);

  // study.csv
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

  // error_vs_time.svg
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
    svg::write_loglog_plot(o, points, title.size() > 110 ? title.substr(0, 107) + "..." : title,
                           "wall time of the run (s)", study.metric.describe, notes);
  });

  // study.json
  json configurations = json::array(), front = json::array();
  std::vector<const Row*> by_time;
  for (const auto& r : rows) {
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
    if (nrmse) item["nrmse"] = {{"ux", number_json(r.nrmse[0])}, {"uy", number_json(r.nrmse[1])}, {"uz", number_json(r.nrmse[2])}};
    else {
      item["value"] = number_json(r.value);
      item["reference_value"] = number_json(r.reference);
    }
    if (!r.message.empty()) item["message"] = r.message;
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
  const double study_seconds = std::chrono::duration<double>(Clock::now() - study_start).count();
  const json report = {{"study", study.file.string()},
                       {"scene", study.scene.string()},
                       {"description", study.description},
                       {"metric", metric},
                       {"reference", reference_json},
                       {"threads", options.threads > 0 ? options.threads : study.threads},
                       {"varied", study.varied},
                       {"configurations", configurations},
                       {"pareto_front", front},
                       {"study_time_s", study_seconds},
                       {"files", {{"table", "study.csv"}, {"plot", "error_vs_time.svg"}, {"runs", "runs"}}}};
  out.write_file("study.json", [&](std::ostream& o) { o << report.dump(2) << "\n"; });

  // The table on stdout.
  std::size_t width = 13;
  for (const auto& r : rows) width = std::max(width, r.configuration->label.size());
  std::cout << fmt::format("{:<{}} {:>13} {:>10} {:>10} {:>13} {:>7}\n", "configuration", width, "status", "wall (s)",
                           "memory MB", study.metric.name, "pareto");
  for (const auto& r : rows)
    std::cout << fmt::format("{:<{}} {:>13} {:>10} {:>10} {:>13} {:>7}\n", r.configuration->label, width, r.status,
                             number_text(r.wall_s, "{:.3g}"), number_text(r.peak_mb, "{:.4g}"),
                             number_text(r.error, "{:.3e}"), r.pareto ? "*" : "");
  std::cout << fmt::format("study: {} configurations in {:.3g} s; {}, {}, {} in {}\n", rows.size(), study_seconds,
                           "study.csv", "study.json", "error_vs_time.svg", out.path().string());
  const bool any_ok = std::any_of(rows.begin(), rows.end(), [](const Row& r) { return r.status == "ok"; });
  if (!any_ok) log().error("no configuration of the study succeeded");
  return any_ok ? 0 : 1;
}

}  // namespace mtled::app
