#include "energy_monitor.hpp"

#include <algorithm>
#include <cmath>

#include "mtled/instability.hpp"
#include "mtled/constraints.hpp"
#include "mtled/interfaces/driver.hpp"
#include "mtled/thread_team.hpp"

namespace mtled {

namespace {
// Room for the one-sided quadrature of the work and for mass scaling; a growing instability passes it within a
// few dozen steps.
constexpr double kMargin = 10.0;
}  // namespace

void EnergyMonitor::after_step(const StepRecord& step) {
  const auto& sets = *step.constraint_sets;
  const auto& previous_values = *step.previous_values;
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const NodalConstraints& set = *sets[s];
    const std::size_t n = std::min({previous_values[s].size(), set.values.size(), set.reactions.size()});
    for (std::size_t k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c)
        if (set.components()[c]) work_bound_ += std::abs(set.reactions[k][c] * (set.values[k][c] - previous_values[s][k][c]));
  }
  // The projection onto the constraints also changes the velocities it touches: the kinetic energy it adds is
  // work the prescribed motion does on the nodes it drives directly. Only additions count: the energy it takes
  // out of a growing mode (at fixed nodes) must not raise the bound that mode is measured against.
  // The kinetic energy central differences conserve: 1/2 v(n-1/2) M v(n+1/2), the product of the two half-step
  // velocities around step n. (The square of one half-step velocity overstates the energy of modes near the
  // stability limit by 1 / (1 - (h omega / 2)^2), which would flag stable runs at large time-step factors.)
  // For a mode that grows, it grows too (in magnitude). Both in one pass over the nodes, shared by the team on
  // large clouds and summed in thread order.
  if (!(step.step_size > 0.0)) return;
  const double scale = step.previous_step_size > 0.0 ? 0.5 / (step.step_size * step.previous_step_size) : 0.0;
  const Model& model = *step.model;
  ThreadTeam& team = model.team();
  const int parts = model.node_count() >= 8192 * team.size() ? team.size() : 1;
  sums_.assign(static_cast<std::size_t>(parts), Sums{});
  const auto pass = [&](int thread) {
    Sums& mine = sums_[static_cast<std::size_t>(thread)];
    const auto [begin, end] = ThreadTeam::share(model.node_count(), thread, parts);
    for (auto i = static_cast<std::size_t>(begin); i < static_cast<std::size_t>(end); ++i) {
      double added = 0.0, product = 0.0;
      for (std::size_t d = 3 * i; d < 3 * i + 3; ++d) {
        const double after = step.u[d] - step.u_previous[d], before = step.u_free[d] - step.u_previous[d];
        added += std::max(0.0, after * after - before * before);
        product += (step.u_previous[d] - step.u_before[d]) * after;
      }
      mine.added += step.mass[i] * added;
      const double e = scale * step.mass[i] * product;
      mine.kinetic += e;
      if (std::abs(e) > mine.fastest_energy) {
        mine.fastest_energy = std::abs(e);
        mine.fastest = static_cast<Index>(i);
      }
    }
  };
  if (parts == 1)
    pass(0);
  else
    team.run(pass);
  double added = 0.0, kinetic = 0.0, fastest_energy = 0.0;
  Index fastest = 0;
  for (const Sums& part : sums_) {
    added += part.added;
    kinetic += part.kinetic;
    if (part.fastest_energy > fastest_energy) {
      fastest_energy = part.fastest_energy;
      fastest = part.fastest;
    }
  }
  work_bound_ += 0.5 * added / (step.step_size * step.step_size);
  kinetic_energy_ = std::abs(kinetic);
  // External force drivers would need their own work; none of the shipped plugins has one.
  if (step.external_forces || !(step.previous_step_size > 0.0)) return;
  if (work_bound_ > 0.0) largest_ratio_ = std::max(largest_ratio_, kinetic_energy_ / work_bound_);
  if (!(kinetic_energy_ > kMargin * work_bound_) || kinetic_energy_ <= 0.0) return;
  throw node_instability(
      step.step, step.time, "energy_growth",
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
