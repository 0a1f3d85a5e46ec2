#pragma once
// Checks the time loop runs after every completed step, each its own small component (in the spirit of
// PETSc's TSMonitorSet): a monitor reads the step just taken, keeps whatever state it needs between steps,
// stops the run by throwing InstabilityError, and reports its own record into summary.json
// ("monitors": {name: record}). The step itself knows none of them.
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "mtled/interfaces/driver.hpp"
#include "mtled/interfaces/integrator.hpp"
#include "mtled/json.hpp"
#include "mtled/types.hpp"

namespace mtled {

class Model;
class ConstraintSystem;

// What a monitor may change in the run it watches: the stable time step the integrator sizes its next steps by
// (DiscreteSystem::stable_time_step). Only ever lowered: the stable-step monitor lowers it when the deformed body
// has become stiffer than the setup estimate allowed for.
class StepControl {
 public:
  virtual ~StepControl();
  virtual void lower_stable_time_step(double stable_time_step) = 0;
};

// A completed step n -> n + 1, as a monitor sees it.
struct StepRecord {
  long step = 0;            // n + 1
  double time = 0.0;        // s, at n + 1
  double step_size = 0.0;   // t(n+1) - t(n)
  double previous_step_size = 0.0;  // t(n) - t(n-1); 0 at the first step
  std::span<const double> u;     // displacements at n + 1 (3 per node)
  std::span<const double> mass;  // per node, as the integrator uses it
  StepSums sums;                 // the step's reductions over the unknowns (increments, energies)
  const Model* model = nullptr;
  // f = f_int(u) for any state u (where the run computes its forces: the CPU, or a backend's device); -1 or the
  // first inadmissible integration point.
  std::function<Index(std::span<const double> u, std::span<double> f)> internal_forces;
  const ConstraintSystem* constraints = nullptr;
  const std::vector<NodalConstraints*>* constraint_sets = nullptr;
  const std::vector<std::vector<Vec3>>* previous_values = nullptr;  // the sets' prescribed values at n
  bool external_forces = false;                                      // some driver applies forces
  std::optional<NeedleStatus> needle;                                // the scene's needle, where it is now
  double stable_time_step = 0.0;  // the stable step in use for the masses in use (before the integrator's factor)
  double time_step_factor = 1.0;  // the integrator's
  double stable_step_margin = 0.9;  // the integrator's: the largest fraction of the stable step it should take
  StepControl* control = nullptr;  // the run's, while the time loop calls the monitors
};

class StepMonitor {
 public:
  virtual ~StepMonitor();
  virtual std::string name() const = 0;
  // Throws InstabilityError (naming the step, what and where) to stop the run.
  virtual void after_step(const StepRecord& step) = 0;
  // After the run's last step (the loop ended normally); may throw as after_step does.
  virtual void after_run(const StepRecord&) {}
  // Its record for summary.json.
  virtual json report() const = 0;
};

}  // namespace mtled
