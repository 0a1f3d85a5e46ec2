#include "energy_monitor.hpp"

#include <algorithm>
#include <cmath>

#include "mtled/instability.hpp"
#include "mtled/interfaces/driver.hpp"

namespace mtled {

namespace {
// Room for the one-sided quadrature of the work and for mass scaling; a growing instability passes it within a
// few dozen steps.
constexpr double kMargin = 10.0;
}  // namespace

void EnergyMonitor::after_step(const StepRecord& step) {
  const auto& sets = run_->constraint_sets;
  const auto& previous_values = step.previous_values;
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const NodalConstraints& set = *sets[s];
    const std::size_t n = std::min({previous_values[s].size(), set.values.size(), set.reactions.size()});
    for (std::size_t k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c)
        if (set.components()[c]) work_bound_ += std::abs(set.reactions[k][c] * (set.values[k][c] - previous_values[s][k][c]));
  }
  // The projection onto the constraints also changes the velocities it touches: the kinetic energy it adds is
  // work the prescribed motion does on the nodes it drives directly (StepSums::projection_energy). Only additions
  // count: the energy it takes out of a growing mode (at fixed nodes) must not raise the bound that mode is measured
  // against. The kinetic energy central differences conserve: 1/2 v(n-1/2) M v(n+1/2), the product of the two
  // half-step velocities around step n (StepSums::kinetic_product). (The square of one half-step velocity overstates
  // the energy of modes near the stability limit by 1 / (1 - (h omega / 2)^2), which would flag stable runs at large
  // time-step factors.) For a mode that grows, it grows too (in magnitude). The step engine sums both where the
  // state lives.
  if (!(step.step_size > 0.0)) return;
  const Discretisation& model = *run_->discretisation;
  const double added = step.sums.projection_energy;
  const Index fastest = step.sums.fastest_node;
  work_bound_ += 0.5 * added / (step.step_size * step.step_size);
  kinetic_energy_ = step.kinetic_energy;
  // External force drivers would need their own work; none of the shipped plugins has one.
  if (run_->external_forces) return;
  if (work_bound_ > 0.0) largest_ratio_ = std::max(largest_ratio_, kinetic_energy_ / work_bound_);
  if (!(kinetic_energy_ > kMargin * work_bound_) || kinetic_energy_ <= 0.0) return;
  throw node_instability(
      step.load.step, step.load.time, "energy_growth",
      fmt::format("kinetic energy {:.4g} J exceeds {:g} times the work the loads have put in ({:.4g} J): the solution "
                  "is growing without bound (the fastest node is {} at {} m); reduce the time-step factor",
                  kinetic_energy_, kMargin, work_bound_, fastest, point_text(model.nodes()[fastest])),
      model, fastest);
}

json EnergyMonitor::report() const {
  return {{"work_bound_J", work_bound_},
          {"kinetic_energy_J", kinetic_energy_},
          {"largest_kinetic_over_work_bound", largest_ratio_},
          {"limit_kinetic_over_work_bound", kMargin}};
}

}  // namespace mtled
