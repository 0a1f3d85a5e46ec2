#include "mtled/io/run_outputs.hpp"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>

#include "mtled/io/derived_fields.hpp"

namespace mtled {

SceneSection output_section() {
  static const ComponentDeclaration declaration = [] {
    std::vector<json> field_names;
    for (const auto& field : derived_fields()) field_names.push_back(field.name);
    ComponentDeclaration d("output", Category::scene);
    d.summary("What a run writes besides summary.json and result.vtu.");
    d.integer("every_steps")
        .defaults(0)
        .non_negative()
        .unit("1")
        .doc("write steps/NNNNNN.vtu and series.pvd every this many steps; 0 writes the final state only")
        .to<&OutputSettings::every_steps>();
    d.integer("history_every_steps")
        .defaults(20)
        .at_least(1)
        .unit("1")
        .doc("add a row to needle.csv and reactions.csv every this many steps (and at the last step)")
        .to<&OutputSettings::history_every_steps>();
    d.string_list("cell_data")
        .defaults(json::array())
        .choices(field_names)
        .doc(
            "per-cell fields in result.vtu and the step files, evaluated at each tet's integration points "
            "(averaged)")
        .to<&OutputSettings::cell_data>();
    d.string("vtu_format")
        .defaults("binary")
        .choices({"binary", "ascii"})
        .doc(
            "how result.vtu and steps/*.vtu store their arrays: \"binary\" (zlib-compressed, appended in base64, as "
            "VTK writes them) or \"ascii\" (text, about three times larger); both exact")
        .to<&OutputSettings::vtu_format>();
    d.string("length_unit")
        .defaults("m")
        .choices({"m", "mm"})
        .doc(
            "unit of the coordinates and displacements in result.vtu and steps/*.vtu: \"m\", or \"mm\", 3D "
            "Slicer's unit, so that a result of a label-map scene loads on top of its image (the file is tagged "
            "LENGTH_UNIT; mtled compare reads it back in metres); stresses stay in Pa")
        .to<&OutputSettings::length_unit>();
    d.file("displacement_field_like")
        .optional()
        .doc(
            "an image (NRRD, NIfTI; the label map the mesh was made from, the pre-operative MRI) on whose grid the "
            "run's displacement is written after the run, as displacement_field.nrrd or .nii.gz (what mtled field "
            "--like IMAGE writes; docs/label-maps.md); the mesh must record its frame, as a label-map mesh does")
        .to<&OutputSettings::displacement_field_like>();
    d.string("displacement_field_format")
        .defaults("nrrd")
        .choices({"nrrd", "nifti"})
        .doc(
            "displacement_field.nrrd (LPS, the form 3D Slicer saves grid transforms in) or displacement_field.nii.gz "
            "(NIfTI, intent DISPVECT, RAS)")
        .to<&OutputSettings::displacement_field_format>();
    d.string("displacement_field_direction")
        .defaults("resampling")
        .choices({"resampling", "forward"})
        .doc(
            "resampling: at each voxel of the deformed body the step back to its reference point, what Slicer and "
            "ITK resample an image with; forward: at each voxel of the reference body where its material goes")
        .to<&OutputSettings::displacement_field_direction>();
    d.number("displacement_field_decay")
        .defaults(0.01)
        .non_negative()
        .unit("m")
        .doc(
            "outside the body the field is the nearest surface value fading to zero over this distance; 0: zero "
            "outside")
        .to<&OutputSettings::displacement_field_decay>();
    return d;
  }();
  return {"output", &declaration};
}

VtuStyle vtu_style(const Parameters& output) {
  const auto settings = output.read<OutputSettings>();
  return {settings.vtu_format == "ascii" ? VtuFormat::ascii : VtuFormat::binary,
          settings.length_unit == "mm" ? LengthUnit::millimetre : LengthUnit::metre};
}

void OutputWriter::after_run(const StepRecord& last) { finish(last); }

void OutputWriter::finish(const StepRecord& last) {
  if (finished_) return;
  finished_ = true;
  complete(last);
}

// ---- history

namespace {

void needle_row(const StepRecord& step, OutputFolder::Stream& stream) {
  const NeedleStatus& s = *step.needle;
  stream.out() << fmt::format("{:.10g},{:.10g},{:.10g},{}\n", step.load.time, s.depth, s.force, to_string(s.phase));
}

void reaction_rows(const StepRecord& step, std::span<const NodalConstraints* const> sets,
                   OutputFolder::Stream& stream) {
  for (const NodalConstraints* set : sets) {
    const Vec3 r = set->total_reaction();
    stream.out() << fmt::format("{:.10g},{},{:.10g},{:.10g},{:.10g}\n", step.load.time, set->name, r[0], r[1], r[2]);
  }
}

}  // namespace

HistoryWriter::HistoryWriter(const OutputFolder& folder, const Parameters& output)
    : folder_(folder), every_(output.read<OutputSettings>().history_every_steps) {}

void HistoryWriter::before_run(const RunContext& run, const StepRecord& initial) {
  constraint_sets_ = run.constraint_sets;
  relaxing_ = run.integrator->report().relaxation.has_value();
  if (initial.needle) {
    needle_ = folder_.open_stream("needle.csv");
    needle_.out() << "time_s,depth_m,force_N,phase\n";
    if (relaxing_) {
      needle_transient_ = folder_.open_stream("needle_transient.csv");
      needle_transient_.out() << "time_s,depth_m,transient_force_N,phase\n";
    }
  }
  if (!constraint_sets_.empty()) {
    reactions_ = folder_.open_stream("reactions.csv");
    reactions_.out() << "time_s,set,fx_N,fy_N,fz_N\n";
    if (relaxing_) {
      reactions_transient_ = folder_.open_stream("reactions_transient.csv");
      reactions_transient_.out() << "time_s,set,transient_fx_N,transient_fy_N,transient_fz_N\n";
    }
  }
  after_step(initial);
}

void HistoryWriter::after_step(const StepRecord& step) {
  if (step.load.step % every_ == 0) record(step);
  if (relaxing_) record_equilibrium(step);
}

void HistoryWriter::complete(const StepRecord& last) {
  if (last_recorded_ != last.load.step) record(last);
  needle_.commit();
  needle_transient_.commit();
  reactions_.commit();
  reactions_transient_.commit();
}

void HistoryWriter::record(const StepRecord& step) {
  last_recorded_ = step.load.step;
  if (needle_.is_open()) needle_row(step, relaxing_ ? needle_transient_ : needle_);
  if (reactions_.is_open()) reaction_rows(step, constraint_sets_, relaxing_ ? reactions_transient_ : reactions_);
}

// needle.csv and reactions.csv rows at each state the relaxation reports steady.
void HistoryWriter::record_equilibrium(const StepRecord& step) {
  if (step.steady_states == steady_states_) return;
  steady_states_ = step.steady_states;
  if (needle_.is_open()) needle_row(step, needle_);
  if (reactions_.is_open()) reaction_rows(step, constraint_sets_, reactions_);
}

// ---- snapshots

SnapshotWriter::SnapshotWriter(const OutputFolder& folder, const Parameters& output, const ForceKernel& kernel)
    : folder_(folder),
      kernel_(kernel),
      every_(output.read<OutputSettings>().every_steps),
      style_(vtu_style(output)),
      cell_data_(output.read<OutputSettings>().cell_data) {}

// The series starts with the initial state.
void SnapshotWriter::before_run(const RunContext&, const StepRecord& initial) { snapshot(initial); }

void SnapshotWriter::after_step(const StepRecord& step) {
  if (reads_displacement(step.load.step)) snapshot(step);
}

// ... and ends with the final state, which the run's last step need not be a multiple of every_steps to reach.
void SnapshotWriter::complete(const StepRecord& last) {
  if (last_snapshot_ != last.load.step) snapshot(last);
  folder_.write_file("series.pvd", [&](std::ostream& out) {
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
    for (const auto& [time, file] : snapshots_)
      out << fmt::format("<DataSet timestep=\"{:.10g}\" file=\"{}\"/>\n", time, file);
    out << "</Collection>\n</VTKFile>\n";
  });
}

void SnapshotWriter::snapshot(const StepRecord& step) {
  const std::string file = fmt::format("steps/{:06d}.vtu", step.load.step);
  std::vector<double> u(step.u.size());
  kernel_.discretisation().interpolate(step.u, u);
  const std::vector<CellField> fields = cell_fields(kernel_, step.u, cell_data_);
  folder_.write_file(file,
                     [&](std::ostream& out) { write_vtu(out, kernel_.discretisation().mesh(), u, fields, style_); });
  snapshots_.emplace_back(step.load.time, file);
  last_snapshot_ = step.load.step;
}

std::vector<std::shared_ptr<OutputWriter>> add_scene_writers(Simulation& simulation, const Scene& scene,
                                                             const OutputFolder& folder) {
  const Parameters& output = scene.section("output");
  std::vector<std::shared_ptr<OutputWriter>> writers;
  writers.push_back(std::make_shared<HistoryWriter>(folder, output));  // opens only the files the run has rows for
  if (output.read<OutputSettings>().every_steps > 0)
    writers.push_back(std::make_shared<SnapshotWriter>(folder, output, simulation.system().force_kernel()));
  for (const auto& writer : writers) simulation.loop().add_monitor(writer);
  return writers;
}

// ---- the final state and the summary

std::vector<double> write_state(const OutputFolder& folder, const std::string& file, const ForceKernel& kernel,
                                std::span<const double> u, const Parameters& output, bool with_cell_data,
                                const std::vector<CellField>& extra_fields) {
  const Discretisation& model = kernel.discretisation();
  std::vector<double> interpolated(u.size());
  model.interpolate(u, interpolated);
  auto fields =
      with_cell_data ? cell_fields(kernel, u, output.read<OutputSettings>().cell_data) : std::vector<CellField>{};
  fields.insert(fields.end(), extra_fields.begin(), extra_fields.end());
  folder.write_file(file, [&](std::ostream& out) { write_vtu(out, model.mesh(), interpolated, fields, vtu_style(output)); });
  return interpolated;
}

namespace {
json vec_json(const Vec3& v) { return json::array({v[0], v[1], v[2]}); }
}  // namespace

RunSummary::RunSummary(const OutputFolder& folder, json header) : folder_(folder), summary_(std::move(header)) {
  summary_["status"] = "running";
  write();
}

void RunSummary::write() const {
  folder_.write_file("summary.json", [&](std::ostream& out) { out << summary_.dump(2) << "\n"; });
}

void RunSummary::record_resources(const PluginCatalog& catalog, double setup_time, double solve_time, double wall_time) {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  summary_["plugins_loaded"] = catalog.loaded_files();
  summary_["setup_time_s"] = setup_time;
  summary_["solve_time_s"] = solve_time;
  summary_["wall_time_s"] = wall_time;
  summary_["peak_rss_mb"] = static_cast<double>(usage.ru_maxrss) / 1024.0;
}

void RunSummary::record_simulation(const Simulation& simulation, double solve_time) {
  const Discretisation& model = simulation.system().discretisation();
  const auto stats = model.points().support;
  summary_["nodes"] = model.node_count();
  summary_["integration_points"] = model.points().count();
  summary_["support_size"] = {{"min", stats.min}, {"mean", stats.mean}, {"max", stats.max}};
  summary_["min_reciprocal_condition"] = stats.min_reciprocal_condition;
  json mesh(model.mesh().statistics);
  const MeshQuality quality = mesh_quality(model.mesh());
  mesh["min_dihedral_angle_deg"] = quality.min_dihedral_angle_deg;
  mesh["min_radius_ratio"] = quality.min_radius_ratio;
  if (!model.mesh().coordinate_system.empty()) mesh["coordinate_system"] = model.mesh().coordinate_system;
  summary_["mesh"] = mesh;
  summary_["backend"] = simulation.system().backend();  // with what it counted over the run
  summary_["steps"] = simulation.system().step();
  summary_["simulated_time_s"] = simulation.system().time();
  summary_["stable_time_step_s"] = simulation.system().unscaled_stable_time_step();
  summary_["constraint_factorisations"] = simulation.system().constraints().factorisations();
  summary_["force_evaluations"] = simulation.system().force_evaluations();
  summary_["monitors"] = simulation.loop().monitor_reports();
  summary_["ip_updates_per_s"] = solve_time > 0 ? static_cast<double>(simulation.system().force_evaluations()) *
                                                      model.points().count() / solve_time
                                                : 0.0;
  const IntegratorReport report = simulation.loop().integrator().report();
  summary_["integrator"] = to_json(report);
  if (report.relaxation) summary_["integrator"]["relaxed_states"] = simulation.system().steady_states();
  summary_["time_step_s"] = report.time_step;
  // Where the needle got to, on every outcome: a run stopped unstable keeps the depth and force it reached.
  if (const auto* needle = simulation.system().needle()) {
    const NeedleStatus s = needle->status();
    summary_["needle"] = {{"final_depth_m", s.depth},
                          {"final_force_N", s.force},
                          {"puncture_depth_m", s.puncture_depth >= 0 ? json(s.puncture_depth) : json(nullptr)},
                          {"phase", to_string(s.phase)},
                          {"driven_nodes", s.driven_nodes}};
  }
}

void RunSummary::record_result(const Simulation& simulation, std::span<const double> u) {
  double max_displacement = 0.0;
  for (std::size_t i = 0; i < u.size(); i += 3)
    max_displacement = std::max(max_displacement, std::sqrt(u[i] * u[i] + u[i + 1] * u[i + 1] + u[i + 2] * u[i + 2]));
  summary_["max_displacement_m"] = max_displacement;
  json reactions = json::object();
  for (const auto* set : simulation.system().constraint_sets()) reactions[set->name] = vec_json(set->total_reaction());
  summary_["final_reactions_N"] = reactions;
}

void RunSummary::record_instability(const Diagnostic& d, const std::string& last_good_state) {
  json where = json::array();
  for (std::size_t i = 0; i < d.coordinates.size(); ++i) {
    json item = {{"coordinates_m", vec_json(d.coordinates[i])}};
    if (i < d.nodes.size()) item["node"] = d.nodes[i];
    if (i < d.integration_points.size()) item["integration_point"] = d.integration_points[i];
    where.push_back(item);
  }
  summary_["status"] = "unstable";
  summary_["diagnostic"] = {{"step", d.step}, {"time_s", d.time}, {"what", d.what}, {"detail", d.detail}, {"where", where}};
  summary_["last_good_state"] = last_good_state;
}

}  // namespace mtled
