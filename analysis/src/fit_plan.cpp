// A fit's plan: the fit file read and checked (docs/calibration.md), every data file read, every experiment's scene
// validated at the start values and at both bounds, every measured point checked against what its run can give,
// all before anything runs. Every problem is collected, each naming the fit file's line and pointer or the data
// file's line.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include "csv_fields.hpp"
#include "mtled/analysis/fit.hpp"
#include "mtled/analysis/scene_sections.hpp"
#include "mtled/errors.hpp"
#include "mtled/markups.hpp"
#include "mtled/point_search.hpp"
#include "mtled/simulation.hpp"

namespace fs = std::filesystem;

namespace mtled::fit {

double Parameter::scaled(double v) const {
  return log_scale ? (std::log10(v) - std::log10(lower)) / (std::log10(upper) - std::log10(lower))
                   : (v - lower) / (upper - lower);
}

double Parameter::slope(double v) const {
  return log_scale ? v * std::log(10.0) * (std::log10(upper) - std::log10(lower)) : upper - lower;
}

double Parameter::value(double s) const {
  s = std::clamp(s, 0.0, 1.0);
  return log_scale ? std::pow(10.0, std::log10(lower) + s * (std::log10(upper) - std::log10(lower)))
                   : lower + s * (upper - lower);
}

namespace {

// The columns each kind of data file needs, and its optional per-datum standard deviation.
struct Columns {
  std::vector<std::string> required;
  std::string sigma;
};

Columns columns_of(Quantity q) {
  switch (q) {
    case Quantity::needle_force:
      return {{"depth_m", "force_N"}, "sigma_N"};
    case Quantity::reaction_force:
      return {{"displacement_m", "force_N"}, "sigma_N"};
    case Quantity::markers:
      return {{"x_m", "y_m", "z_m", "ux_m", "uy_m", "uz_m"}, "sigma_m"};
  }
  return {};
}

class FitReader {
 public:
  FitReader(const fs::path& file, const std::vector<std::string>& overrides, const std::vector<fs::path>& plugin_paths)
      : file_(file), overrides_(overrides), plugin_paths_(plugin_paths) {}

  Plan read() {
    Plan plan;
    plan.file = fs::absolute(file_);
    plan.document = read_scene(file_, overrides_);  // a JSON file with its lines, --set applied
    document_ = &plan.document;
    const json& root = plan.document.root;
    if (!root.is_object()) throw InputError(file_.string(), "a fit file is a JSON object (docs/calibration.md)");
    check_keys(root, "",
               {"description", "parameters", "experiments", "method", "threads", "concurrent_runs", "timeout_s", "launcher"});
    plan.description = root.value("description", "");
    read_experiments(root, plan.experiments);
    read_parameters(root, plan.experiments, plan.parameters);
    read_settings(root, plan.parameters.size(), plan.settings);
    if (problems_.empty())
      for (std::size_t x = 0; x < plan.experiments.size(); ++x)
        check_experiment(plan.experiments[x], x, plan.parameters);
    if (!problems_.empty()) throw InputError(problems_);
    return plan;
  }

 private:
  void problem(const std::string& pointer, const std::string& message) {
    problems_.push_back({document_->locate(pointer), message});
  }

  void check_keys(const json& object, const std::string& where, const std::set<std::string>& keys) {
    for (const auto& [key, value] : object.items())
      if (!keys.count(key)) {
        const std::string hint = did_you_mean(key, std::vector<std::string>(keys.begin(), keys.end()));
        problem(where + "/" + key, fmt::format("unknown key \"{}\"{}", key, hint.empty() ? "" : "; " + hint));
      }
  }

  std::optional<double> number(const json& object, const std::string& key, const std::string& where, bool required) {
    if (!object.contains(key)) {
      if (required) problem(where + "/" + key, "required: a number");
      return std::nullopt;
    }
    if (!object[key].is_number() || !std::isfinite(object[key].get<double>())) {
      problem(where + "/" + key, "a finite number");
      return std::nullopt;
    }
    return object[key].get<double>();
  }

  void read_experiments(const json& root, std::vector<Experiment>& out) {
    if (!root.contains("experiments") || !root["experiments"].is_array() || root["experiments"].empty()) {
      problem("/experiments", "required: a list of experiments, each {\"name\", \"scene\", \"data\", \"compare\"}");
      return;
    }
    std::set<std::string> names;
    for (std::size_t i = 0; i < root["experiments"].size(); ++i) {
      const std::string where = fmt::format("/experiments/{}", i);
      const json& item = root["experiments"][i];
      if (!item.is_object()) {
        problem(where, "an object {\"name\", \"scene\", \"data\", \"compare\", \"sigma\"}");
        continue;
      }
      check_keys(item, where, {"name", "scene", "set", "data", "compare", "sigma", "sigma_relative", "weight"});
      Experiment e;
      e.where = where;
      e.name = item.value("name", fmt::format("experiment{}", i));
      if (!names.insert(e.name).second) problem(where + "/name", fmt::format("\"{}\" names two experiments", e.name));
      read_compare(item, where, e);
      e.scene = file_at(item, "scene", where + "/scene");
      const json data = item.value("data", json());
      if (e.quantity == Quantity::markers && data.is_object()) {  // two 3D Slicer markups files
        check_keys(data, where + "/data", {"before", "after"});
        e.markups_before = file_at(data, "before", where + "/data/before");
        e.data_file = file_at(data, "after", where + "/data/after");
      } else {
        e.data_file = file_at(item, "data", where + "/data");
      }
      if (item.contains("set")) {
        if (!item["set"].is_object())
          problem(where + "/set", "an object of {\"/json/pointer\": value} scene overrides");
        else
          e.set = item["set"];
      }
      read_compare(item, where, e);
      read_sigma(item, where, e);
      out.push_back(std::move(e));
    }
  }

  // A file named by object[key], relative to the fit file's folder; empty (and a problem) when absent or missing.
  fs::path file_at(const json& object, const char* key, const std::string& pointer) {
    if (!object.contains(key) || !object[key].is_string()) {
      problem(pointer, fmt::format("required: the {} file, relative to the fit file's folder", key));
      return {};
    }
    const fs::path path = (plan_folder() / object[key].get<std::string>()).lexically_normal();
    if (!fs::is_regular_file(path)) {
      problem(pointer, fmt::format("no such file: {}", path.string()));
      return {};
    }
    return path;
  }

  void read_compare(const json& item, const std::string& where, Experiment& e) {
    const json compare = item.value("compare", json());
    const std::string type = compare.is_string() ? compare.get<std::string>() : compare.value("type", "");
    static const std::vector<std::string> kTypes = {"needle_force", "reaction_force", "markers"};
    if (type == "needle_force")
      e.quantity = Quantity::needle_force;
    else if (type == "reaction_force")
      e.quantity = Quantity::reaction_force;
    else if (type == "markers")
      e.quantity = Quantity::markers;
    else {
      const std::string hint = did_you_mean(type, kTypes);
      problem(where + "/compare",
              fmt::format("\"{}\" is not a measured quantity: one of needle_force, reaction_force "
                          "({{\"type\": \"reaction_force\", \"set\": NAME, \"component\": \"z\"}}), "
                          "markers{}",
                          type, hint.empty() ? "" : "; " + hint));
      return;
    }
    if (e.quantity != Quantity::reaction_force) return;
    if (!compare.is_object() || !compare.contains("set") || !compare["set"].is_string()) {
      problem(where + "/compare/set", "required: the name of the constrained set whose reaction was measured");
      return;
    }
    e.set_name = compare["set"].get<std::string>();
    const std::string component = compare.value("component", "z");
    e.component = component == "x" ? 0 : component == "y" ? 1 : component == "z" ? 2 : -1;
    if (e.component < 0) problem(where + "/compare/component", "one of \"x\", \"y\", \"z\"");
  }

  // One of: "sigma" (the data's standard deviation, in their unit), "sigma_relative" (a fraction of each datum's
  // magnitude: a load cell's "1% of reading"), "weight" (relative weights: the residuals then estimate the variance);
  // a sigma column in the data file overrides it per datum.
  void read_sigma(const json& item, const std::string& where, Experiment& e) {
    if (int(item.contains("sigma")) + int(item.contains("sigma_relative")) + int(item.contains("weight")) > 1)
      problem(where, "give one of \"sigma\" (the data's standard deviation), \"sigma_relative\" or \"weight\"");
    const auto sigma = number(item, "sigma", where, false);
    const auto relative = number(item, "sigma_relative", where, false);
    const auto weight = number(item, "weight", where, false);
    if (sigma && *sigma <= 0.0) problem(where + "/sigma", "a standard deviation > 0, in the data's unit (m or N)");
    if (relative && (*relative <= 0.0 || *relative >= 1.0))
      problem(where + "/sigma_relative", "a fraction of each datum in (0, 1), such as 0.01 for 1%");
    if (weight && *weight <= 0.0) problem(where + "/weight", "a weight > 0");
    e.sigma_given = sigma.has_value() || relative.has_value();
    if (relative) e.sigma_relative = *relative;
    if (relative && e.quantity == Quantity::markers)
      problem(where + "/sigma_relative", "markers take an absolute \"sigma\" (m): the imaging's resolution");
    const double s = sigma ? *sigma : weight ? 1.0 / std::sqrt(*weight) : 1.0;
    if (e.data_file.empty()) return;
    if (!e.markups_before.empty())
      read_markups_pair(e, s > 0.0 ? s : 1.0);
    else
      read_data(e, s > 0.0 ? s : 1.0);
  }

  // Markers placed in 3D Slicer on the image before and after: each label's displacement, at its position before.
  void read_markups_pair(Experiment& e, double sigma) {
    MarkupsPoints before, after;
    try {
      before = read_markups(e.markups_before);
      after = read_markups(e.data_file);
    } catch (const InputError& error) {
      problems_.insert(problems_.end(), error.problems().begin(), error.problems().end());
      return;
    }
    if (before.frame != after.frame)
      problems_.push_back({e.data_file.string(), fmt::format("its points are in {} and the \"before\" file's in {}: "
                                                             "save both in one frame",
                                                             after.frame, before.frame)});
    e.markups_frame = before.frame;
    for (std::size_t i = 0; i < after.points.size(); ++i) {
      const std::string where = fmt::format("{}: /markups/0/controlPoints/{}", e.data_file.string(), i);
      const auto& label = after.points[i].label;
      const auto match = std::find_if(before.points.begin(), before.points.end(),
                                      [&](const MarkupsPoint& p) { return p.label == label; });
      if (label.empty() || match == before.points.end()) {
        problems_.push_back({where, fmt::format("no point labelled \"{}\" in {}: markers are matched by label", label,
                                                e.markups_before.string())});
        continue;
      }
      for (int c = 0; c < 3; ++c) {
        Datum d;
        d.position = match->position;
        d.component = c;
        d.label = label;
        d.value = after.points[i].position[c] - match->position[c];
        d.sigma = sigma;
        d.source = where;
        e.data.push_back(d);
      }
    }
    if (e.data.empty()) problems_.push_back({e.data_file.string(), "no marker is in both files"});
  }

  // The data file: a header naming the columns, then one row per datum (markers: three data per row).
  void read_data(Experiment& e, double sigma) {
    std::ifstream in(e.data_file);
    const std::string name = e.data_file.string();
    std::string line;
    int number = 0;
    std::vector<std::string> header;
    while (header.empty() && std::getline(in, line)) {
      ++number;
      if (line.find_first_not_of(" \t\r") != std::string::npos && line[line.find_first_not_of(" \t\r")] != '#')
        header = csv_fields(line);
    }
    const Columns wanted = columns_of(e.quantity);
    std::vector<int> index;
    for (const auto& c : wanted.required) {
      const auto it = std::find(header.begin(), header.end(), c);
      if (it == header.end()) {
        problems_.push_back({fmt::format("{}:{}", name, number),
                             fmt::format("no column \"{}\"; a {} file has the columns {}{}", c, kind_name(e.quantity),
                                         fmt::join(wanted.required, ","),
                                         fmt::format(" (optional: {}{})", wanted.sigma,
                                                     e.quantity == Quantity::markers ? ", label" : ""))});
        return;
      }
      index.push_back(static_cast<int>(it - header.begin()));
    }
    const auto sigma_it = std::find(header.begin(), header.end(), wanted.sigma);
    const int sigma_column = sigma_it == header.end() ? -1 : static_cast<int>(sigma_it - header.begin());
    if (sigma_column >= 0) e.sigma_given = true;
    const auto label_it = std::find(header.begin(), header.end(), "label");
    const int label_column = label_it == header.end() ? -1 : static_cast<int>(label_it - header.begin());
    while (std::getline(in, line)) {
      ++number;
      if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t\r")] == '#')
        continue;
      read_row(e, csv_fields(line), index, sigma_column, label_column, sigma, fmt::format("{}:{}", name, number));
    }
    if (e.data.empty() && !header.empty()) problems_.push_back({name, "no data rows under the header"});
  }

  static const char* kind_name(Quantity q) {
    return q == Quantity::needle_force ? "needle_force" : q == Quantity::reaction_force ? "reaction_force" : "markers";
  }

  void read_row(Experiment& e, const std::vector<std::string>& fields, const std::vector<int>& index, int sigma_column,
                int label_column, double sigma, const std::string& where) {
    auto value_of = [&](int column, double& out) {
      const std::string text = column < static_cast<int>(fields.size()) ? fields[static_cast<std::size_t>(column)] : "";
      char* end = nullptr;
      out = std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(out)) {
        problems_.push_back({where, fmt::format("column {} is \"{}\": a finite number is needed", column + 1, text)});
        return false;
      }
      return true;
    };
    std::vector<double> v(index.size());
    for (std::size_t k = 0; k < index.size(); ++k)
      if (!value_of(index[k], v[k])) return;
    double s = sigma;
    if (sigma_column >= 0 && !value_of(sigma_column, s)) return;
    // Relative to a datum of 0 (a template for --synthesize): left open, the model's value sets it.
    if (sigma_column < 0 && e.sigma_relative > 0.0) s = v[1] != 0.0 ? e.sigma_relative * std::abs(v[1]) : NAN;
    if (s <= 0.0) {
      problems_.push_back({where, "the standard deviation must be > 0"});
      return;
    }
    if (e.quantity != Quantity::markers) {
      Datum d;
      d.abscissa = v[0];
      d.value = v[1];
      d.sigma = s;
      d.source = where;
      e.data.push_back(d);
      return;
    }
    const std::string label = label_column >= 0 && label_column < static_cast<int>(fields.size())
                                  ? fields[static_cast<std::size_t>(label_column)]
                                  : fmt::format("marker{}", e.data.size() / 3 + 1);
    for (int c = 0; c < 3; ++c) {
      Datum d;
      d.position = Vec3(v[0], v[1], v[2]);
      d.component = c;
      d.label = label;
      d.value = v[3 + c];
      d.sigma = s;
      d.source = where;
      e.data.push_back(d);
    }
  }

  void read_parameters(const json& root, const std::vector<Experiment>& experiments, std::vector<Parameter>& out) {
    if (!root.contains("parameters") || !root["parameters"].is_array() || root["parameters"].empty()) {
      problem("/parameters",
              "required: a list of parameters, each {\"name\", \"pointer\", \"lower\", \"upper\", "
              "\"start\"}");
      return;
    }
    std::set<std::string> names;
    for (std::size_t i = 0; i < root["parameters"].size(); ++i) {
      const std::string where = fmt::format("/parameters/{}", i);
      const json& item = root["parameters"][i];
      if (!item.is_object()) {
        problem(where, "an object {\"name\", \"pointer\", \"lower\", \"upper\", \"start\", \"log\"}");
        continue;
      }
      check_keys(item, where, {"name", "pointer", "lower", "upper", "start", "log"});
      Parameter p;
      p.name = item.value("name", fmt::format("p{}", i));
      if (!names.insert(p.name).second) problem(where + "/name", fmt::format("\"{}\" names two parameters", p.name));
      read_pointers(item, where, experiments, p);
      const auto lower = number(item, "lower", where, true), upper = number(item, "upper", where, true);
      const auto start = number(item, "start", where, true);
      if (item.contains("log") && !item["log"].is_boolean()) problem(where + "/log", "true or false");
      p.log_scale = item.value("log", false) == true;
      if (!lower || !upper || !start) continue;
      p.lower = *lower;
      p.upper = *upper;
      p.start = *start;
      if (!(p.lower < p.upper))
        problem(where + "/upper", fmt::format("the bounds are inverted or equal: lower {:g}, upper {:g}; "
                                              "give lower < upper",
                                              p.lower, p.upper));
      else if (p.start < p.lower || p.start > p.upper)
        problem(where + "/start", fmt::format("{:g} is outside the bounds [{:g}, {:g}]", p.start, p.lower, p.upper));
      if (p.log_scale && p.lower <= 0.0)
        problem(where + "/lower", "a parameter searched on a log scale needs bounds > 0");
      out.push_back(std::move(p));
    }
  }

  void read_pointers(const json& item, const std::string& where, const std::vector<Experiment>& experiments,
                     Parameter& p) {
    p.pointers.assign(experiments.size(), "");
    const json pointer = item.value("pointer", json());
    auto valid = [&](const json& v, const std::string& at) {
      const bool ok = v.is_string() && !v.get<std::string>().empty() && v.get<std::string>()[0] == '/';
      if (!ok) problem(at, "a JSON pointer into the scene, such as \"/needle/deformation_coefficient\"");
      return ok;
    };
    if (pointer.is_object()) {  // its own pointer in each experiment that it enters
      for (const auto& [name, v] : pointer.items()) {
        const auto it =
            std::find_if(experiments.begin(), experiments.end(), [&](const Experiment& e) { return e.name == name; });
        if (it == experiments.end()) {
          problem(where + "/pointer/" + name, fmt::format("no experiment is named \"{}\"", name));
          continue;
        }
        if (valid(v, where + "/pointer/" + name))
          p.pointers[static_cast<std::size_t>(it - experiments.begin())] = v.get<std::string>();
      }
      return;
    }
    if (valid(pointer, where + "/pointer")) std::fill(p.pointers.begin(), p.pointers.end(), pointer.get<std::string>());
  }

  // "launcher": a non-empty list of strings whose first names a program on PATH (or a path to one).
  void read_launcher(const json& root, std::vector<std::string>& launcher) {
    if (!root.contains("launcher")) return;
    const json& l = root["launcher"];
    const bool strings =
        l.is_array() && !l.empty() && std::all_of(l.begin(), l.end(), [](const json& v) { return v.is_string(); });
    if (!strings) {
      problem("/launcher", "a list of strings: the command put before each forward run, e.g. [\"srun\", \"-N\", \"1\", "
                           "\"-n\", \"1\", \"--exclusive\"] or [\"mpirun\", \"-np\", \"4\"]");
      return;
    }
    launcher = l.get<std::vector<std::string>>();
    const fs::path program = find_program(launcher.front());
    if (program.empty())
      problem("/launcher/0", fmt::format("\"{}\" is neither an executable file nor a program on PATH", launcher.front()));
    else
      launcher.front() = program.string();
  }

  void read_settings(const json& root, std::size_t parameter_count, Settings& s) {
    const auto count = [&](const json& object, const std::string& key, const std::string& where, int minimum,
                           int& out) {
      if (!object.contains(key)) return;
      if (!object[key].is_number_integer() || object[key].get<int>() < minimum)
        problem(where + "/" + key, fmt::format("a whole number >= {}", minimum));
      else
        out = object[key].get<int>();
    };
    count(root, "threads", "", 0, s.threads);
    count(root, "concurrent_runs", "", 0, s.concurrent_runs);
    if (auto t = number(root, "timeout_s", "", false)) s.timeout_s = *t;
    read_launcher(root, s.launcher);
    if (!root.contains("method")) return;
    const json& m = root["method"];
    if (!m.is_object()) {
      problem("/method", "an object {\"type\": \"levenberg_marquardt\" or \"bobyqa\", \"max_evaluations\", ...}");
      return;
    }
    check_keys(m, "/method", {"type", "max_evaluations", "tolerance", "fd_step", "starts"});
    const std::string type = m.value("type", "levenberg_marquardt");
    if (type == "bobyqa")
      s.method = Method::bobyqa;
    else if (type != "levenberg_marquardt")
      problem("/method/type", fmt::format("\"{}\": one of levenberg_marquardt, bobyqa", type));
    count(m, "max_evaluations", "/method", 2, s.max_evaluations);
    if (auto t = number(m, "tolerance", "/method", false)) {
      if (*t <= 0.0 || *t >= 1.0) problem("/method/tolerance", "a relative tolerance in (0, 1)");
      s.tolerance = *t;
    }
    if (auto h = number(m, "fd_step", "/method", false)) {
      if (*h <= 0.0 || *h > 0.25) problem("/method/fd_step", "a step in (0, 0.25] of the parameter's (scaled) range");
      s.fd_step = *h;
    }
    if (m.contains("starts")) read_starts(m["starts"], parameter_count, s);
  }

  // Further start points, each a list of parameter values in the parameters' order.
  void read_starts(const json& starts, std::size_t parameter_count, Settings& s) {
    if (!starts.is_array()) {
      problem("/method/starts", "a list of start points, each a list of the parameters' values in their order");
      return;
    }
    for (std::size_t i = 0; i < starts.size(); ++i) {
      const std::string where = fmt::format("/method/starts/{}", i);
      const json& point = starts[i];
      if (!point.is_array() || point.size() != parameter_count ||
          !std::all_of(point.begin(), point.end(), [](const json& v) { return v.is_number(); })) {
        problem(where, fmt::format("a list of {} numbers, one per parameter", parameter_count));
        continue;
      }
      s.extra_starts.push_back(point.get<std::vector<double>>());
    }
  }

  fs::path plan_folder() const { return fs::absolute(file_).parent_path(); }

  // The experiment's scene at the start values, and at each parameter's bounds, validated as a run would; the
  // pointers name values there; the data lie where the run gives values.
  void check_experiment(Experiment& e, std::size_t x, const std::vector<Parameter>& parameters) {
    SceneDocument document = read_scene(e.scene);
    for (const auto& [pointer, value] : e.set.items()) apply_override(document, pointer + "=" + value.dump());
    for (std::size_t k = 0; k < parameters.size(); ++k) {
      const std::string& pointer = parameters[k].pointers[x];
      if (!pointer.empty() && !document.root.contains(json::json_pointer(pointer)))
        problem(fmt::format("/parameters/{}/pointer", k),
                fmt::format("{} names nothing in {} (experiment \"{}\"): give the value in the scene, or in the "
                            "experiment's \"set\"",
                            pointer, e.scene.filename().string(), e.name));
    }
    if (!problems_.empty()) return;
    PluginCatalog catalog(plugin_search_path(plugin_paths_, scene_plugin_paths(document)));
    std::optional<Scene> scene;
    for (const char* at : {"start", "lower", "upper"}) {
      SceneDocument d = document;
      for (const auto& p : parameters) {
        const std::string& pointer = p.pointers[x];
        const double v = std::string(at) == "start" ? p.start : std::string(at) == "lower" ? p.lower : p.upper;
        if (!pointer.empty()) apply_override(d, fmt::format("{}={:.17g}", pointer, v));
      }
      try {
        Scene s = validate_scene(std::move(d), catalog, run_scene_sections());
        if (!scene) scene = std::move(s);
      } catch (const InputError& error) {
        for (const auto& p : error.problems())
          problem(e.where + "/scene",
                  fmt::format("the scene with the parameters at their {} values: {}: {}", at, p.where, p.message));
        return;
      }
    }
    check_data_range(e, *scene);
    if (e.quantity == Quantity::markers) check_markers_inside(e, *scene, catalog);
  }

  void check_data_range(Experiment& e, const Scene& scene) {
    const json& root = scene.document.root;
    e.relaxed_increments = root["integrator"].value("relaxed_increments", 1);
    if (e.quantity == Quantity::needle_force) {
      if (!scene.needle) {
        problem(e.where + "/compare", fmt::format("the scene {} has no needle", e.scene.filename().string()));
        return;
      }
      e.depth_full = root["needle"].value("depth", 0.0);
      for (const auto& d : e.data)
        if (d.abscissa < 0.0 || d.abscissa > e.depth_full * (1.0 + 1e-9))
          problems_.push_back({d.source, fmt::format("depth {:g} m is outside the run's range [0, {:g}] m (the scene's "
                                                     "/needle/depth); raise the depth in the experiment's \"set\"",
                                                     d.abscissa, e.depth_full)});
      return;
    }
    if (e.quantity != Quantity::reaction_force) return;
    if (root["integrator"].value("type", "") != "dynamic_relaxation") {
      problem(e.where + "/compare",
              "a reaction force against displacement is read at the relaxed states: the scene's "
              "integrator must be dynamic_relaxation");
      return;
    }
    const json* boundary = nullptr;
    for (const auto& b : root["boundaries"])
      if (b.value("name", "") == e.set_name) boundary = &b;
    if (!boundary || !boundary->contains("displacement")) {
      problem(e.where + "/compare/set", fmt::format("no boundary named \"{}\" with a prescribed \"displacement\" in {}",
                                                    e.set_name, e.scene.filename().string()));
      return;
    }
    e.displacement_full = (*boundary)["displacement"][static_cast<std::size_t>(e.component)].get<double>();
    const double lo = std::min(0.0, e.displacement_full), hi = std::max(0.0, e.displacement_full);
    for (const auto& d : e.data)
      if (d.abscissa < lo - 1e-12 || d.abscissa > hi + 1e-12)
        problems_.push_back(
            {d.source, fmt::format("displacement {:g} m is outside the run's range [{:g}, {:g}] m (set \"{}\", "
                                   "component {}, signed as in the scene)",
                                   d.abscissa, lo, hi, e.set_name, "xyz"[e.component])});
  }

  // A marker must lie in the body: inside one of the mesh's tets (a marker outside would be extrapolated).
  void check_markers_inside(Experiment& e, const Scene& scene, PluginCatalog& catalog) {
    const TetMesh mesh = load_scene_mesh(scene, catalog);
    // Markups in the other of Slicer's frames than the mesh records: into the mesh's (as the needle's trajectory).
    if (frames_differ(e.markups_frame, mesh.coordinate_system)) {
      for (auto& d : e.data) {
        d.position = flip_lps_ras(d.position);
        if (d.component < 2) d.value = -d.value;
      }
      e.markups_frame = mesh.coordinate_system;
    }
    std::vector<Vec3> centroids(mesh.tets.size());
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) centroids[t] = tet_centroid(mesh, static_cast<Index>(t));
    const PointSearch search(centroids);
    std::vector<Index> near;
    for (std::size_t i = 0; i < e.data.size(); i += 3) {
      const Vec3& x = e.data[i].position;
      search.nearest(x, 48, near);
      const bool inside = std::any_of(near.begin(), near.end(), [&](Index t) { return inside_tet(mesh, t, x); });
      if (!inside)
        problems_.push_back(
            {e.data[i].source, fmt::format("marker \"{}\" at ({:g}, {:g}, {:g}) m is outside the body of {}",
                                           e.data[i].label, x[0], x[1], x[2], e.scene.filename().string())});
    }
  }

  static bool inside_tet(const TetMesh& mesh, Index t, const Vec3& x) {
    const auto& tet = mesh.tets[static_cast<std::size_t>(t)];
    const Vec3& a = mesh.points[static_cast<std::size_t>(tet[0])];
    Eigen::Matrix3d m;
    for (int k = 0; k < 3; ++k) m.col(k) = mesh.points[static_cast<std::size_t>(tet[k + 1])] - a;
    const Vec3 b = m.fullPivLu().solve(x - a);
    const double tol = 1e-9;
    return b.minCoeff() >= -tol && b.sum() <= 1.0 + tol;
  }

  fs::path file_;
  std::vector<std::string> overrides_;
  std::vector<fs::path> plugin_paths_;
  const SceneDocument* document_ = nullptr;
  std::vector<Problem> problems_;
};

}  // namespace

Plan read(const fs::path& file, const std::vector<std::string>& overrides, const std::vector<fs::path>& plugin_paths) {
  return FitReader(file, overrides, plugin_paths).read();
}

void check_measured(const Plan& plan) {
  std::vector<Problem> problems;
  for (const auto& e : plan.experiments)
    for (const auto& d : e.data)
      if (!std::isfinite(d.sigma))
        problems.push_back({d.source,
                            "a measured value of 0 has no relative standard deviation: give a sigma column, or "
                            "\"sigma\" instead of \"sigma_relative\""});
  if (!problems.empty()) throw InputError(problems);
}

}  // namespace mtled::fit
