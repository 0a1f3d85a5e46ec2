#pragma once
// A scene built into a running simulation: the mesh, the meshless model, the drivers (boundary conditions
// and the needle), the integrator and the state. Integrators advance the state through the services
// below; the kernel's loop (run) checks stability and calls the observer between steps.
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "mtled/constraints.hpp"
#include "mtled/interfaces/integrator.hpp"
#include "mtled/json.hpp"
#include "mtled/model.hpp"
#include "mtled/scene.hpp"

namespace mtled {

struct StepObserver {
  virtual ~StepObserver();
  virtual void on_step(const class Simulation& simulation) = 0;
};

class Simulation final : public DiscreteSystem {
 public:
  Simulation(const Scene& scene, PluginCatalog& catalog);
  ~Simulation() override;
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // ---- the DiscreteSystem the integrator advances
  std::span<const double> displacement() const override { return u_; }
  std::span<const double> previous_displacement() const override { return u_previous_; }
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

  const Model& model() const { return *model_; }
  double load_fraction() const { return load_.load_fraction; }

  // ---- the loop and what outputs read
  void run(StepObserver* observer);
  TimeIntegrator& integrator() { return *integrator_; }
  const TimeIntegrator& integrator() const { return *integrator_; }
  const NeedleModel* needle() const { return needle_.get(); }
  const std::vector<NodalConstraints*>& constraint_sets() const { return constraint_sets_; }
  const ConstraintSystem& constraints() const { return *constraint_system_; }
  double unscaled_stable_time_step() const { return unscaled_stable_time_step_; }
  long force_evaluations() const { return force_evaluations_; }
  // Kinetic energy at the last step (J), the form central differences conserve: 1/2 v(n-1/2) . M v(n+1/2), the
  // product of the half-step velocities around it (0 before the second step).
  double kinetic_energy() const { return kinetic_energy_; }
  // Interpolated displacement at every node (3 per node).
  std::vector<double> interpolated_displacement() const;
  // The stable-step monitor's record for summary.json (null when /monitors/stable_step_every_steps is 0).
  json stable_step_report() const;

 private:
  void update_drivers();
  void check_finite(std::span<const double> u_new, double new_time) const;
  // Stops the run (InstabilityError "energy_growth") when the kinetic energy exceeds what the loads put in.
  void check_energy(std::span<const double> u_new, double step_size);
  // Stops the run (InstabilityError "time_step_above_stable") when the step exceeds 2 / sqrt(lambda_max) of
  // M^-1 K at the current state, lambda_max estimated by Lanczos iteration on force differences.
  void check_stable_step(double step_size);

  std::unique_ptr<Model> model_;
  std::vector<std::shared_ptr<BoundaryCondition>> boundaries_;
  std::shared_ptr<NeedleModel> needle_;
  std::vector<Driver*> drivers_;
  std::vector<NodalConstraints*> constraint_sets_;
  std::vector<NodalForces*> force_sets_;
  std::unique_ptr<ConstraintSystem> constraint_system_;
  std::shared_ptr<TimeIntegrator> integrator_;

  LoadState load_;
  std::vector<double> u_, u_previous_;
  std::vector<double> mass_;
  bool mass_changed_ = true;
  double stable_time_step_ = 0.0;
  double unscaled_stable_time_step_ = 0.0;
  long force_evaluations_ = 0;
  std::vector<std::vector<Vec3>> previous_values_;  // prescribed values of the previous step, per set
  // Bound on the work the constraints have done (J): sum of |reaction . increment of the prescribed value| and of
  // |kinetic energy the constraint projection added|.
  double work_bound_ = 0.0;
  double kinetic_energy_ = 0.0;
  double previous_step_size_ = 0.0;
  // Per-thread parts of check_energy's sums.
  struct EnergySums {
    double added = 0.0, kinetic = 0.0, fastest_energy = 0.0;
    Index fastest = 0;
  };
  std::vector<EnergySums> energy_sums_;
  std::vector<double> u_free_;  // this step's displacements before the constraint projection

  long stable_step_every_ = 0;
  int stable_step_iterations_ = 0;
  double perturbation_length_ = 0.0;  // largest nodal perturbation of the force differences (m)
  std::vector<double> mode_;          // the last Ritz vector of the fastest mode, the next check's start
  long stable_step_checks_ = 0, monitor_force_evaluations_ = 0;
  double last_stable_step_ = 0.0, smallest_stable_step_ = INFINITY;
  long smallest_stable_step_at_ = 0;
};

}  // namespace mtled
