#pragma once
// A scene built into a running simulation: the mesh, the meshless model, the drivers (boundary conditions
// and the needle), the integrator, the monitors added to it and the state. Integrators advance the state through the
// DiscreteSystem below; the kernel's loop (run) calls the monitors and the observer after each step.
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "mtled/constraints.hpp"
#include "mtled/interfaces/backend.hpp"
#include "mtled/interfaces/integrator.hpp"
#include "mtled/json.hpp"
#include "mtled/model.hpp"
#include "mtled/monitor.hpp"
#include "mtled/scene.hpp"

namespace mtled {

struct StepObserver {
  virtual ~StepObserver();
  virtual void on_step(const class Simulation& simulation) = 0;
};

class Simulation final : public DiscreteSystem, private StepControl {
 public:
  Simulation(const Scene& scene, PluginCatalog& catalog);
  ~Simulation() override;
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // ---- the DiscreteSystem the integrator advances; the state lives in the step engine (the CPU's, or a backend's)
  std::span<const double> displacement() const override { return engine_->displacement(); }
  std::span<const double> previous_displacement() const override { return engine_->previous_displacement(); }
  std::span<const double> mass() const override { return mass_; }
  long step() const override { return load_.step; }
  double time() const override { return load_.time; }
  // Critical time step (before any safety factor) for the current masses: min over integration points.
  double stable_time_step() const override { return stable_time_step_; }
  // Raises the density at each integration point so that its critical step is the largest one's.
  void equalise_critical_steps() override;
  // Throws InstabilityError naming the integration point when F is inadmissible (J <= 0).
  void internal_forces(std::span<const double> u, std::span<double> f) override;
  bool has_external_forces() const override { return !force_sets_.empty(); }
  void external_forces(std::span<double> f) override;
  // Drivers update for (new_time, new_load_fraction), u_new is corrected to satisfy every constraint
  // (reactions = correction / alpha), then becomes the current state.
  void complete_step(std::span<double> u_new, double new_time, double new_load_fraction, double alpha) override;
  void steady_state_reached() override { ++steady_states_; }
  // The fused form both shipped integrators use: the engine's passes, with only the sums coming back.
  IncrementSums evaluate_forces(bool increment_sums) override;
  StepSums advance(double alpha, double beta, double new_time, double new_load_fraction) override;

  const Model& model() const { return *model_; }
  double load_fraction() const { return load_.load_fraction; }
  // summary.json's "backend": the engine's own account (type, device, threads).
  json backend() const { return engine_->describe(); }

  // ---- the loop and what outputs read
  void run(StepObserver* observer);
  TimeIntegrator& integrator() { return *integrator_; }
  const TimeIntegrator& integrator() const { return *integrator_; }
  const NeedleModel* needle() const { return needle_.get(); }
  const std::vector<NodalConstraints*>& constraint_sets() const { return constraint_sets_; }
  const ConstraintSystem& constraints() const { return *constraint_system_; }
  double unscaled_stable_time_step() const { return unscaled_stable_time_step_; }
  long force_evaluations() const { return force_evaluations_; }
  // Equilibria the integrator reported so far (one per relaxed load increment of dynamic relaxation).
  long steady_states() const { return steady_states_; }
  // The step just completed, as the monitors see it.
  StepRecord last_step() const;
  // Interpolated displacement at every node (3 per node).
  std::vector<double> interpolated_displacement() const;
  // Monitors run after every step in the order added (mtled/monitors/scene_monitors.hpp adds a scene's).
  void add_monitor(std::unique_ptr<StepMonitor> monitor);
  const StepMonitor* monitor(std::string_view name) const;  // null when none has that name
  // Every monitor's record for summary.json, by name.
  json monitor_reports() const;

 private:
  void build_model(const Scene& scene, PluginCatalog& catalog, TetMesh mesh,
                   std::vector<std::shared_ptr<const Material>> materials);
  void build_drivers(const Scene& scene, PluginCatalog& catalog);
  void build_engine(const Scene& scene, PluginCatalog& catalog);
  void update_drivers();
  // The step's end up to the new state: the load state moves on, the drivers update, the constraints correct the
  // engine's prediction.
  void project(double new_time, double new_load_fraction, double alpha);
  void lower_stable_time_step(double stable_time_step) override;
  // Stop the run with an InstabilityError: an inadmissible F at integration point `bad` of state u ("inverted_material"
  // or "non_finite"), or a non-finite unknown of the update.
  [[noreturn]] void inadmissible(Index bad, std::span<const double> u) const;
  [[noreturn]] void not_finite(std::int64_t unknown, double value, double new_time) const;

  std::unique_ptr<Model> model_;
  std::vector<std::shared_ptr<BoundaryCondition>> boundaries_;
  std::shared_ptr<NeedleModel> needle_;
  std::vector<Driver*> drivers_;
  std::vector<NodalConstraints*> constraint_sets_;
  std::vector<NodalForces*> force_sets_;
  std::unique_ptr<ConstraintSystem> constraint_system_;
  std::shared_ptr<TimeIntegrator> integrator_;
  std::shared_ptr<StepEngine> engine_;

  LoadState load_;
  std::vector<double> mass_;
  std::vector<double> f_ext_;  // when some driver applies forces
  StepSums sums_;              // of the step just completed
  bool mass_changed_ = true;
  double stable_time_step_ = 0.0;
  double unscaled_stable_time_step_ = 0.0;
  long force_evaluations_ = 0;
  long steady_states_ = 0;
  std::vector<std::vector<Vec3>> previous_values_;  // prescribed values of the previous step, per set
  double step_size_ = 0.0, previous_step_size_ = 0.0;
  double time_step_factor_ = 1.0;  // the integrator's, read once it is initialised
  double stable_step_margin_ = 0.9;  // the integrator's
  std::vector<std::unique_ptr<StepMonitor>> monitors_;
};

}  // namespace mtled
