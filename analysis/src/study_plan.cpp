// A study's plan: the study file read and checked (docs/studies.md), every configuration's scene validated before
// anything runs.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <set>

#include "mtled/analysis/result_file.hpp"
#include "mtled/analysis/study.hpp"
#include "mtled/errors.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/analysis/scene_sections.hpp"
#include "mtled/scene.hpp"
#include "study_support.hpp"

namespace fs = std::filesystem;

namespace mtled::study {

namespace {

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

class StudyReader {
 public:
  explicit StudyReader(const fs::path& file) : file_(file) {}

  Study read() {
    const json root = parse();
    Study study;
    study.file = fs::absolute(file_);
    study.description = root.value("description", "");
    read_scene_and_run_settings(root, study);
    const json common = root.contains("set") ? read_set(root["set"], "/set") : json::object();
    if (root.contains("configurations")) read_configurations(root["configurations"], common, study.configurations);
    if (root.contains("sweep")) read_sweep(root["sweep"], sweep_order(), common, study.configurations);
    if (study.configurations.empty() && problems_.empty())
      problem("/configurations", "the study has no configurations: give \"configurations\" or \"sweep\"");
    const std::set<std::string> folders = assign_folders(study.configurations);
    if (read_metric(root, study.metric)) read_reference(root.value("reference", json()), common, study);
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

  json parse() {
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
    return root;
  }

  void read_scene_and_run_settings(const json& root, Study& study) {
    if (!root.contains("scene") || !root["scene"].is_string()) {
      problem("/scene", "required: the scene file, relative to the study file's folder");
    } else {
      study.scene = (study.file.parent_path() / root["scene"].get<std::string>()).lexically_normal();
      if (!fs::is_regular_file(study.scene)) problem("/scene", fmt::format("no such scene file: {}", study.scene.string()));
    }
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
  }

  void read_configurations(const json& list, const json& common, std::vector<Configuration>& out) {
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
      out.push_back(std::move(c));
    }
  }

  // The sweep's axes in the file's order (json objects are sorted): the last varies fastest.
  std::vector<std::string> sweep_order() const {
    std::ifstream again(file_);
    const auto ordered = nlohmann::ordered_json::parse(again, nullptr, false, true);
    std::vector<std::string> order;
    if (ordered.is_object() && ordered.contains("sweep") && ordered["sweep"].is_object())
      for (const auto& item : ordered["sweep"].items()) order.push_back(item.key());
    return order;
  }

  // Each configuration's folder under runs/ from its label; labels and folders unique.
  std::set<std::string> assign_folders(std::vector<Configuration>& configurations) {
    std::set<std::string> labels, folders;
    for (auto& c : configurations) {
      c.folder = folder_name(c.label);
      if (c.label.empty()) problem(c.where + "/label", "must not be empty");
      if (!labels.insert(c.label).second) problem(c.where + "/label", fmt::format("\"{}\" is used twice", c.label));
      else if (!folders.insert(c.folder).second)
        problem(c.where + "/label", fmt::format("\"{}\" gives the same folder name as another label", c.label));
    }
    return folders;
  }
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

  // The metric, from "metric" (a name or an object), completed by the "exact_force" shorthand of "reference":
  // {"exact_force": {"set": "top", "component": "z", "value": -0.06}}.
  // False when the metric is unusable, so that the reference is not judged against it.
  bool read_metric(const json& root, Metric& m) {
    json metric = root.value("metric", json("nrmse"));
    if (metric.is_string()) metric = json{{"type", metric}};
    const json reference = root.value("reference", json());
    if (reference.is_object() && reference.contains("exact_force")) {
      const json& e = reference["exact_force"];
      if (!e.is_object() || !e.contains("value") || !e["value"].is_number()) {
        problem("/reference/exact_force", "needs \"set\", \"component\" and a numeric \"value\" (N)");
        return false;
      }
      if (!metric.contains("set")) metric["set"] = e.value("set", "");
      if (!metric.contains("component")) metric["component"] = e.value("component", "");
      if (metric.value("type", "") != "force_error")
        problem("/metric", "\"exact_force\" goes with the metric \"force_error\"");
    }
    if (!metric.is_object() || !metric.contains("type") || !metric["type"].is_string()) {
      problem("/metric", "\"nrmse\", \"force_error\" or \"summary_error\" (or an object with \"type\")");
      return false;
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
      return false;
    }
    return true;
  }

  void read_reference(const json& reference, const json& common, Study& study) {
    Reference& r = study.reference;
    const Metric& m = study.metric;
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

}  // namespace

Study read(const fs::path& file) { return StudyReader(file).read(); }

void check_scenes(Study& study, const std::vector<fs::path>& plugin_paths) {
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
      PluginCatalog catalog(plugin_search_path(plugin_paths, scene_plugin_paths(document)));
      validate_scene(std::move(document), catalog, run_scene_sections());
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

}  // namespace mtled::study
