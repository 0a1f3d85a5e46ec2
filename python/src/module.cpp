// _mtled: the compiled half of the Python package `mtled` (python/mtled/__init__.py is the other): scene documents,
// a run in this process with a Python callback between steps, and the run's state as read-only NumPy arrays over
// mtled's own memory. The GIL is released while a run steps and re-taken for the callback.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <atomic>
#include <cmath>
#include <csignal>

#include "commands.hpp"
#include "in_process_run.hpp"
#include "mtled/analysis/compare.hpp"
#include "mtled/discretisation.hpp"
#include "mtled/log.hpp"
#include "mtled/version.hpp"
#include "processes.hpp"

namespace py = pybind11;
namespace fs = std::filesystem;
using namespace pybind11::literals;

namespace mtled::python {

using app::InProcessRun;
using app::RunRequest;
using app::SceneText;

namespace {

// Set by Ctrl-C while a run on the main thread holds SIGINT, or by request_interrupt(): every run in this process
// stops at its next step with status "interrupted".
std::atomic<bool> interrupt_requested{false};
extern "C" void stop_runs_on_interrupt(int) { interrupt_requested = true; }

// Ctrl-C for the length of a run on the main thread: the run ends cleanly at its next step (Python's own handler
// would only run once the run had returned).
class SigintHold {
 public:
  explicit SigintHold(bool hold) : hold_(hold) {
    if (!hold_) return;
    interrupt_requested = false;
    previous_ = std::signal(SIGINT, stop_runs_on_interrupt);
  }
  ~SigintHold() {
    if (hold_) std::signal(SIGINT, previous_);
  }
  SigintHold(const SigintHold&) = delete;
  SigintHold& operator=(const SigintHold&) = delete;

 private:
  bool hold_;
  void (*previous_)(int) = SIG_DFL;
};

// An (n, 3) read-only array over `values` (3 per row), which `owner` keeps alive: no copy.
py::array rows_of_three(const double* values, std::size_t count, py::handle owner) {
  const auto rows = static_cast<py::ssize_t>(count / 3);
  py::array view(py::dtype::of<double>(), {rows, py::ssize_t{3}},
                 {static_cast<py::ssize_t>(3 * sizeof(double)), static_cast<py::ssize_t>(sizeof(double))}, values,
                 owner);
  view.attr("setflags")("write"_a = false);
  return view;
}

py::array rows_of_three(const std::vector<Vec3>& points, py::handle owner) {
  return rows_of_three(points.empty() ? nullptr : points.front().data(), 3 * points.size(), owner);
}

// The field of a run's written state at each of `points` ((n, 3), m, in the reference body): its displacement (n, 3)
// and F (n, 3, 3), NaN where no node's support covers a point.
py::tuple field_at_points(const InProcessRun& r,
                          const py::array_t<double, py::array::c_style | py::array::forcecast>& points) {
  if (points.ndim() != 2 || points.shape(1) != 3)
    throw py::value_error(
        fmt::format("field_at: points must be an (n, 3) array of coordinates (m), not of shape ({})",
                    fmt::join(std::vector<py::ssize_t>(points.shape(), points.shape() + points.ndim()), ", ")));
  const std::span<const double> state = r.run().written_state();
  if (state.empty()) throw py::value_error("field_at: the run wrote no state (result.vtu or last_good_state.vtu)");
  const auto n = points.shape(0);
  py::array_t<double> displacement({n, py::ssize_t{3}});
  py::array_t<double> gradient({n, py::ssize_t{3}, py::ssize_t{3}});
  const double* x = points.data();
  double* u_out = displacement.mutable_data();
  double* f_out = gradient.mutable_data();
  {
    const py::gil_scoped_release released;
    const Discretisation& discretisation = r.simulation().system().discretisation();
    for (py::ssize_t p = 0; p < n; ++p) {
      const auto sample = field_at(discretisation, Vec3(x[3 * p], x[3 * p + 1], x[3 * p + 2]), state);
      for (int i = 0; i < 3; ++i) {
        u_out[3 * p + i] = sample ? sample->displacement[i] : NAN;
        for (int j = 0; j < 3; ++j) f_out[9 * p + 3 * i + j] = sample ? sample->deformation_gradient(i, j) : NAN;
      }
    }
  }
  return py::make_tuple(displacement, gradient);
}

py::object from_json(const json& value) { return py::module_::import("json").attr("loads")(value.dump()); }

// Problems as Python sees them: (where, message) pairs, which mtled.errors locates.
std::vector<std::pair<std::string, std::string>> where_and_message(const std::vector<Problem>& problems) {
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const Problem& p : problems) pairs.emplace_back(p.where, p.message);
  return pairs;
}

// The user's callback after every `every`-th step: it sees the step, the time, the load fraction, the needle and the
// displacement (a view valid during the call); returning False stops the run ("stopped"). An exception it raises ends
// the run ("failed") and is raised again, as it was, once the run has recorded that.
class PythonCallback final : public StepMonitor {
 public:
  PythonCallback(py::object callback, long every) : callback_(std::move(callback)), every_(every) {}
  std::string name() const override { return "python_callback"; }
  bool reads_displacement(long step) const override { return !callback_.is_none() && step % every_ == 0; }
  void after_step(const StepRecord& step) override {
    if (interrupt_requested) throw app::RunStopped("interrupted", "interrupted (Ctrl-C)");
    if (callback_.is_none() || step.load.step % every_ != 0) return;
    py::gil_scoped_acquire gil;
    bool stop = false;
    try {
      stop = call(step).ptr() == Py_False;
    } catch (py::error_already_set& e) {
      raised_ = std::current_exception();
      throw std::runtime_error(fmt::format("the Python callback raised at step {}: {}", step.load.step, e.what()));
    }
    if (stop) throw app::RunStopped("stopped", fmt::format("stopped by the callback at step {}", step.load.step));
  }
  // The callback's own exception, when it raised one.
  void raise_callback_error() const {
    if (raised_) std::rethrow_exception(raised_);
  }
  // Released with the GIL held (the run that holds this monitor may end on another thread).
  void release() {
    py::gil_scoped_acquire gil;
    callback_ = py::none();
  }

 private:
  py::object call(const StepRecord& step) const {
    py::object needle = py::none();
    if (step.needle)
      needle = py::dict("depth"_a = step.needle->depth, "force"_a = step.needle->force,
                        "phase"_a = to_string(step.needle->phase));
    // The step's own memory, valid for this call only: no owner to keep alive (None stands in as the base).
    return callback_(step.load.step, step.load.time, step.load.load_fraction, needle,
                     rows_of_three(step.u.data(), step.u.size(), py::none()));
  }
  py::object callback_;
  long every_;
  std::exception_ptr raised_;
};

std::unique_ptr<InProcessRun> run_scene(const SceneText& scene, const fs::path& output, int threads, long every,
                                        py::object callback, const std::vector<fs::path>& plugin_paths,
                                        bool hold_sigint) {
  if (every < 1) throw py::value_error(fmt::format("every={}: the callback's step interval must be at least 1", every));
  auto observer = std::make_shared<PythonCallback>(std::move(callback), every);
  const RunRequest request{output, threads, plugin_paths, {observer}};
  std::unique_ptr<InProcessRun> run;
  try {
    const SigintHold sigint(hold_sigint);
    const py::gil_scoped_release released;
    run = std::make_unique<InProcessRun>(scene, request);
  } catch (...) {
    observer->raise_callback_error();
    throw;
  }
  observer->release();
  return run;
}

py::dict reactions(const InProcessRun& run, py::handle owner) {
  py::dict sets;
  for (const NodalConstraints* set : run.simulation().system().constraint_sets())
    sets[py::str(set->name)] = rows_of_three(set->reactions, owner);
  return sets;
}

void bind_scene(py::module_& m) {
  py::class_<SceneText>(m, "SceneText")
      .def_static("read",
                  [](const fs::path& file) {
                    return SceneText{read_scene(file), {}};
                  })
      .def_static("parse",
                  [](const std::string& text, const std::string& name, const std::optional<fs::path>& directory) {
                    SceneText scene{parse_scene(text, name), {}};
                    // Relative paths in the scene are read from `directory`: the document's as if it were a file.
                    if (directory) scene.document.file = fs::absolute(*directory) / name;
                    return scene;
                  })
      .def("set",
           [](SceneText& scene, const std::string& pointer, const std::string& value_json) {
             const std::string assignment = pointer + "=" + value_json;
             apply_override(scene.document, assignment);
             scene.assignments.push_back(assignment);
           })
      .def("copy", [](const SceneText& scene) { return scene; })
      .def_property_readonly("json", [](const SceneText& scene) { return scene.document.root.dump(); })
      .def_property_readonly("name", [](const SceneText& scene) { return scene.document.name; })
      .def("problems", [](const SceneText& scene, const std::vector<fs::path>& plugin_paths) {
        return where_and_message(app::scene_problems(scene.document, plugin_paths));
      });
}

void bind_run(py::module_& m) {
  py::class_<InProcessRun>(m, "InProcessRun")
      .def_property_readonly("status", &InProcessRun::status)
      .def_property_readonly("summary", [](const InProcessRun& r) { return from_json(r.run().summary()); })
      .def_property_readonly("folder", [](const InProcessRun& r) { return r.run().folder(); })
      .def_property_readonly("nodes",
                             [](py::object self) {
                               const auto& r = self.cast<const InProcessRun&>();
                               return rows_of_three(r.simulation().system().discretisation().mesh().points, self);
                             })
      .def_property_readonly("displacement",
                             [](py::object self) {
                               const auto u = self.cast<const InProcessRun&>().run().written_displacement();
                               return rows_of_three(u.data(), u.size(), self);
                             })
      .def_property_readonly("reactions",
                             [](py::object self) { return reactions(self.cast<const InProcessRun&>(), self); })
      .def("field_at", &field_at_points, "points"_a);
  m.def("run", &run_scene, "scene"_a, "output"_a, "threads"_a, "every"_a, "callback"_a, "plugin_paths"_a,
        "hold_sigint"_a);
  m.def("request_interrupt", [](bool requested) { interrupt_requested = requested; });
}

// mtled study and mtled fit as the command line runs them (a study's runs child `mtled run`s, a fit's in this process);
// the exit code.
void bind_studies(py::module_& m) {
  m.def(
      "study",
      [](const fs::path& study, const fs::path& output, int threads, bool reuse,
         const std::vector<fs::path>& plugin_paths, const std::string& log_level) {
        app::StudyOptions options;
        options.study = study;
        options.output = output;
        options.threads = threads;
        options.reuse = reuse;
        options.plugin_paths = plugin_paths;
        options.log_level = log_level;
        const py::gil_scoped_release released;
        return app::study_command(options);
      },
      "study"_a, "output"_a, "threads"_a, "reuse"_a, "plugin_paths"_a, "log_level"_a);
  m.def(
      "fit",
      [](const fs::path& fit, const fs::path& output, const std::vector<std::string>& overrides, int threads,
         std::optional<unsigned long long> synthesize, const std::vector<fs::path>& plugin_paths,
         const std::string& log_level) {
        app::FitOptions options;
        options.fit = fit;
        options.output = output;
        options.overrides = overrides;
        options.threads = threads;
        options.synthesize = synthesize;
        options.plugin_paths = plugin_paths;
        options.log_level = log_level;
        const py::gil_scoped_release released;
        return app::fit_command(options);
      },
      "fit"_a, "output"_a, "overrides"_a, "threads"_a, "synthesize"_a, "plugin_paths"_a, "log_level"_a);
}

}  // namespace

}  // namespace mtled::python

PYBIND11_MODULE(_mtled, m) {
  using namespace mtled;
  m.doc() = "mtled's compiled half; use the package `mtled`";
  m.attr("__version__") = MTLED_VERSION_STRING;
  app::join_processes({});  // one process: the commands that would share work find it alone
  py::register_exception_translator([](std::exception_ptr raised) {
    try {
      if (raised) std::rethrow_exception(raised);
    } catch (const InputError& e) {
      const py::object error =
          py::module_::import("mtled.errors").attr("InputError")(e.what(), python::where_and_message(e.problems()));
      PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
    }
  });
  python::bind_scene(m);
  python::bind_run(m);
  m.def("set_log_level", &set_log_level, "level"_a);
  m.def("compare", [](const fs::path& a, const fs::path& b, const std::vector<fs::path>& plugin_paths) {
    PluginCatalog catalog(plugin_search_path(plugin_paths, {}));
    return python::from_json(comparison_json(compare_runs(a, b, catalog)));
  });
  python::bind_studies(m);
}
