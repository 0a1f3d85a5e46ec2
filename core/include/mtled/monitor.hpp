#pragma once
// What the time loop calls after every completed step, each its own small component (in the spirit of PETSc's
// TSMonitorSet): a monitor reads the step just taken, keeps whatever state it needs between steps, stops the run by
// throwing InstabilityError, and reports its own record into summary.json ("monitors": {name: record}); an output
// writer records the step into its files. The step itself knows none of them.
#include <cmath>
#include <cstdint>
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

class Discretisation;
class TimeIntegrator;

// for_each_share(n, body): body(begin, end) over shares of 0 .. n - 1, on several threads or on the caller.
using ForEachShare =
    std::function<void(std::int64_t n, const std::function<void(std::int64_t begin, std::int64_t end)>& body)>;

// What a monitor may change in the run it watches: the stable time step the integrator sizes its next steps by
// (DiscreteSystem::stable_time_step). The stable-step monitor lowers it when the deformed body has become stiffer
// than the setup estimate allowed for, and under "follow" raises it while a steady-state integrator holds its loads
// (docs/stability.md).
class StepControl {
 public:
  virtual ~StepControl();
  virtual void set_stable_time_step(double stable_time_step) = 0;
};

// What a monitor may use for the whole run, handed to it once, in before_run, and valid until the run ends: the
// discretisation and the integrator, the constraint sets (their prescribed values and reactions are those of the
// latest step whenever a monitor is called), the run's force evaluation and constraint projection, its threads, and
// the step-size control.
struct RunContext {
  const Discretisation* discretisation = nullptr;
  const TimeIntegrator* integrator = nullptr;  // the run's (its report())
  std::span<const NodalConstraints* const> constraint_sets;
  bool external_forces = false;     // some driver applies forces
  double time_step_factor = 1.0;    // the integrator's
  double stable_step_margin = 0.9;  // the integrator's: the largest fraction of the stable step it should take
  // f = f_int(u) for any state u (where the run computes its forces: the CPU, or a backend's device); -1 or the
  // first inadmissible integration point.
  std::function<Index(std::span<const double> u, std::span<double> f)> internal_forces;
  // Removes from v (3 per node) what the constraints hold: the subspace the constrained dynamics live in.
  std::function<void(std::span<double> v)> project_out;
  // Runs body(begin, end) over shares of 0 .. n - 1 on the run's threads (the time step's team); empty: body(0, n).
  // A sum split by these shares would depend on the thread count: sum fixed chunks and add them in order instead.
  ForEachShare for_each_share;
  StepControl* step_control = nullptr;  // the step-size adaptation beside the integrator
};

// A completed step n -> n + 1, as a monitor or writer sees it: plain data.
struct StepRecord {
  LoadState load;                // step n + 1, its time (s) and load fraction
  double step_size = 0.0;        // t(n+1) - t(n)
  long steady_states = 0;        // equilibria the integrator reported so far (relaxed load increments)
  std::span<const double> u;     // displacements at n + 1 (3 per node); empty on steps no monitor reads it
  std::span<const double> mass;  // per node, as the integrator uses it
  StepSums sums;                 // the step's reductions over the unknowns (increments, energies)
  // The kinetic energy central differences conserve (J): 1/2 v(n-1/2) . M v(n+1/2), the product of the two
  // half-step velocities around step n (StepSums::kinetic_product); 0 before the second step.
  double kinetic_energy = 0.0;
  // Each constraint set's prescribed values at n (RunContext::constraint_sets has those at n + 1): the work the
  // prescribed motions did this step is sum |reaction . (value(n+1) - value(n))| over the constrained components.
  std::span<const std::vector<Vec3>> previous_values;
  std::optional<NeedleStatus> needle;  // the scene's needle, where it is now
  double stable_time_step = 0.0;       // the stable step in use for the masses in use (before the integrator's factor)
};

// Called by the time loop around every completed step: the checks (mtled/monitors: energy growth, the stable step,
// folds) and the output writers (mtled/io/run_outputs.hpp: history CSVs, snapshots), in the order added. The step
// itself knows none of them.
class StepMonitor {
 public:
  virtual ~StepMonitor();
  virtual std::string name() const = 0;
  // Once, with what the monitor may use for the whole run and the initial state (step 0), before the first step.
  virtual void before_run(const RunContext&, const StepRecord&) {}
  // Throws InstabilityError (naming the step, what and where) to stop the run.
  virtual void after_step(const StepRecord& step) = 0;
  // Whether after_step reads StepRecord::u at this step (n + 1). An engine that spreads the nodes over processes
  // gathers the whole displacement only on steps some monitor reads it, and StepRecord::u is empty on the others
  // (before_run and after_run always have it). The default: every step.
  virtual bool reads_displacement(long step) const;
  // After the run's last step (the loop ended normally); may throw as after_step does.
  virtual void after_run(const StepRecord&) {}
  // Its record for summary.json's "monitors" (null: none; writers have none).
  virtual json report() const { return nullptr; }
};

}  // namespace mtled
