#pragma once
// Always on: stops a run whose kinetic energy exceeds what the loads can have put in (InstabilityError
// "energy_growth"). Damping only removes energy, so kinetic plus strain energy never exceed the work of the
// prescribed motions; a growing instability passes that bound within a few dozen steps.
#include "mtled/monitor.hpp"

namespace mtled {

class EnergyMonitor final : public StepMonitor {
 public:
  std::string name() const override { return "energy"; }
  void before_run(const RunContext& run, const StepRecord&) override { run_ = &run; }
  void after_step(const StepRecord& step) override;
  bool reads_displacement(long) const override { return false; }
  json report() const override;

 private:
  const RunContext* run_ = nullptr;
  double work_bound_ = 0.0;  // J: sum of |reaction . increment of the prescribed value| and of the kinetic
                             // energy the constraint projection added
  double kinetic_energy_ = 0.0;  // at the last step (StepRecord::kinetic_energy)
  double largest_ratio_ = 0.0;  // of the kinetic energy to the work bound, over the run
};

}  // namespace mtled
