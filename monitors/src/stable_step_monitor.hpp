#pragma once
// /monitors/stable_step_every_steps: re-estimates the stable step of the current, deformed body,
// 2 / sqrt(lambda_max(M^-1 K)), at step 1 and every that many steps. /monitors/stable_step "adapt" lowers the
// integrator's step to its margin of the estimate (IntegratorReport::stable_step_margin) when the step is above
// that (StepControl); "follow" (the default) does the same and, while a steady-state integrator holds its loads,
// also raises the step to that margin (re-estimating once at the start of each hold); "stop" ends the run
// (InstabilityError "time_step_above_stable") when the time step exceeds the estimate by more than 5%
// (docs/stability.md).
#include <cmath>
#include <memory>
#include <vector>

#include "mtled/monitor.hpp"
#include "mtled/parameters.hpp"

namespace mtled {

class StableStepMonitor final : public StepMonitor {
 public:
  // Its parameters in the scene's "monitors" section, read into Settings.
  static void declare(ComponentDeclaration& d);
  struct Settings {
    long stable_step_every_steps = 0;
    std::string stable_step;  // one of the choices (validated)
    int stable_step_iterations = 0;
  };
  // The monitor the section asks for; null when stable_step_every_steps is 0.
  static std::unique_ptr<StableStepMonitor> from_section(const Parameters& monitors, const Discretisation& model);
  // `perturbation_length`: the largest nodal perturbation of the force differences (m).
  enum class Response { stop, adapt, follow };
  StableStepMonitor(long every, int iterations, double perturbation_length, Response response)
      : every_(every), iterations_(iterations), perturbation_length_(perturbation_length), response_(response) {}
  std::string name() const override { return "stable_step"; }
  // "follow" raises only a steady-state integrator's step (IntegratorReport::relaxation): its time is fictitious.
  // For any other it acts as "adapt".
  void before_run(const RunContext& run, const StepRecord&) override {
    run_ = &run;
    raises_ =
        response_ == Response::follow && run.integrator != nullptr && run.integrator->report().relaxation.has_value();
  }
  void after_step(const StepRecord& step) override {
    if (raises_) follow_loads(step);
    if (reads_displacement(step.load.step)) check(step);
  }
  bool reads_displacement(long step) const override {
    return step == 1 || step % every_ == 0 || step == hold_check_at_;
  }
  json report() const override;

 private:
  void check(const StepRecord& step);
  // "follow": notes whether the step held the loads (its load fraction equal to the previous step's); schedules a
  // re-estimate for the step after a hold begins, and when the loads move again, takes back what was raised.
  void follow_loads(const StepRecord& step);
  // lambda_max of M^-1 K at the step's state (0 when it cannot be estimated); keeps its mode for the next check.
  double largest_eigenvalue(const StepRecord& step);
  // Throws the InstabilityError "time_step_above_stable", naming where the fastest mode is largest.
  [[noreturn]] void refuse(const StepRecord& step) const;

  const RunContext* run_ = nullptr;
  long every_;
  int iterations_;
  double perturbation_length_;
  Response response_;
  bool raises_ = false;          // "follow" with a steady-state integrator (before_run)
  long lowered_ = 0;             // times the step was lowered
  double lowest_step_ = INFINITY;  // the smallest step it was lowered to (s)
  long raised_ = 0;              // times the step was raised ("follow")
  double highest_step_ = 0.0;    // the largest step it was raised to (s)
  // "follow": the previous step's load fraction, whether the loads are held, the step at which the hold's first
  // re-estimate is due, and the stable step in use before the hold's first raise (0: not raised in this hold).
  double previous_load_fraction_ = NAN;
  bool held_ = false;
  long hold_check_at_ = -1;
  double stable_before_raise_ = 0.0;
  double setup_estimate_ = 0.0;
  std::vector<double> mode_;  // the last Ritz vector of the fastest mode, the next check's start
  long checks_ = 0, force_evaluations_ = 0;
  double last_stable_step_ = 0.0, smallest_stable_step_ = INFINITY;
  long smallest_stable_step_at_ = 0;
};

}  // namespace mtled
