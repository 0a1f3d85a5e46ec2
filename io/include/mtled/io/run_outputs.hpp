#pragma once
// What a run writes, as components the time loop drives like the monitors (StepMonitor): the history CSVs
// (needle.csv, reactions.csv and, under dynamic relaxation, their _transient variants), the snapshots (steps/*.vtu
// and series.pvd), the final state (result.vtu, or last_good_state.vtu when a run stops unstable) and summary.json.
// The scene's "output" section is declared here, beside them (docs/files.md describes every file).
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "mtled/errors.hpp"
#include "mtled/io/output.hpp"
#include "mtled/monitor.hpp"
#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"

namespace mtled {

// The "output" section of a scene (validate_scene), declared by the writers; its values, Parameters::read.
SceneSection output_section();
struct OutputSettings {
  long every_steps = 0;
  long history_every_steps = 0;
  std::vector<std::string> cell_data;
  std::string vtu_format, length_unit;
  std::optional<std::filesystem::path> displacement_field_like;
  std::string displacement_field_format, displacement_field_direction;
  double displacement_field_decay = 0.0;
};
VtuStyle vtu_style(const Parameters& output);

// A StepMonitor that records steps into files. finish() completes them with the run's last state (once); the time
// loop calls it after the run's last step, and whoever stops a run calls it too, so that a run that ends unstable
// keeps its history up to the last state.
class OutputWriter : public StepMonitor {
 public:
  void after_run(const StepRecord& last) final;
  void finish(const StepRecord& last);

 private:
  virtual void complete(const StepRecord& last) = 0;
  bool finished_ = false;
};

// needle.csv and reactions.csv: a row every /output/history_every_steps steps and at the last. Under an integrator
// that relaxes (dynamic relaxation) they hold each relaxed state (forces in equilibrium), and needle_transient.csv and
// reactions_transient.csv the rows along the way.
class HistoryWriter final : public OutputWriter {
 public:
  HistoryWriter(const OutputFolder& folder, const Parameters& output);
  std::string name() const override { return "history"; }
  void before_run(const RunContext& run, const StepRecord& initial) override;
  void after_step(const StepRecord& step) override;
  bool reads_displacement(long) const override { return false; }

 private:
  void complete(const StepRecord& last) override;
  void record(const StepRecord& step);
  void record_equilibrium(const StepRecord& step);

  const OutputFolder& folder_;
  long every_;
  std::span<const NodalConstraints* const> constraint_sets_;  // the run's (before_run)
  bool relaxing_ = false;
  long last_recorded_ = -1, steady_states_ = 0;
  OutputFolder::Stream needle_, needle_transient_, reactions_, reactions_transient_;
};

// steps/NNNNNN.vtu every /output/every_steps steps (from the initial state to the last), and series.pvd listing them.
class SnapshotWriter final : public OutputWriter {
 public:
  SnapshotWriter(const OutputFolder& folder, const Parameters& output, const ForceKernel& kernel);
  std::string name() const override { return "snapshots"; }
  void before_run(const RunContext& run, const StepRecord& initial) override;
  void after_step(const StepRecord& step) override;
  bool reads_displacement(long step) const override { return step % every_ == 0 && step > 0; }

 private:
  void complete(const StepRecord& last) override;
  void snapshot(const StepRecord& step);

  const OutputFolder& folder_;
  const ForceKernel& kernel_;  // the stress the forces used, for the cell data
  long every_;
  VtuStyle style_;
  std::vector<std::string> cell_data_;  // the cell fields each step file carries, as result.vtu does
  long last_snapshot_ = -1;
  std::vector<std::pair<double, std::string>> snapshots_;
};

// The writers the scene's output section asks for, added to the simulation's loop (none when it asks for none).
std::vector<std::shared_ptr<OutputWriter>> add_scene_writers(Simulation& simulation, const Scene& scene,
                                                             const OutputFolder& folder);

// `file` (result.vtu, last_good_state.vtu): the mesh with the interpolated displacement of nodal parameters u, the
// scene's cell data (with_cell_data) and `extra_fields` (the folded tets of a stopped run). Returns the interpolated
// displacement (3 per node).
std::vector<double> write_state(const OutputFolder& folder, const std::string& file, const ForceKernel& kernel,
                                std::span<const double> u, const Parameters& output, bool with_cell_data,
                                const std::vector<CellField>& extra_fields = {});

// summary.json, written at the start with status "running" and again at the end with the outcome, so that it always
// says how the run ended. Each record_* adds what it names; write() replaces the file.
class RunSummary {
 public:
  RunSummary(const OutputFolder& folder, json header);
  json& operator[](const std::string& key) { return summary_[key]; }
  const json& contents() const { return summary_; }
  void write() const;
  // What every outcome records: the times (s), the peak memory, the plugins loaded.
  void record_resources(const PluginCatalog& catalog, double setup_time, double solve_time, double wall_time);
  // The model, the steps, the monitors' records, the integrator's report and where the needle got to.
  void record_simulation(const Simulation& simulation, double solve_time);
  // The final state: the largest of the interpolated displacements u (3 per node) and the reactions.
  void record_result(const Simulation& simulation, std::span<const double> u);
  // Status "unstable": what stopped the run and where, and the file holding the last good state.
  void record_instability(const Diagnostic& diagnostic, const std::string& last_good_state);

 private:
  const OutputFolder& folder_;
  json summary_;
};

}  // namespace mtled
