#include "mtled/analysis/postprocess.hpp"

#include <algorithm>
#include <cmath>


namespace mtled {

// The run's own error indicators, beside its timings (docs/studies.md): how far from equilibrium and from
// rest the final state is, and the time step against the stable one.
json error_indicators(Simulation& simulation) {
  const IntegratorReport integrator = simulation.loop().integrator().report();
  json out = json::object();
  // Global equilibrium: every constraint reaction and external force together vanish at a steady state with
  // plain quadrature; consistent integration leaves a quadrature error that falls under refinement
  // (docs/studies.md). Measured against the largest reaction.
  Vec3 total = Vec3::Zero();
  double largest = 0.0;
  for (const auto* set : simulation.system().constraint_sets()) {
    total += set->total_reaction();
    for (const auto& r : set->reactions) largest = std::max(largest, r.norm());
  }
  if (simulation.system().has_external_forces()) {
    std::vector<double> f(simulation.system().displacement().size());
    simulation.system().external_forces(f);
    for (std::size_t i = 0; i < f.size(); ++i) total[static_cast<int>(i % 3)] += f[i];
  }
  out["net_force_N"] = json::array({total[0], total[1], total[2]});
  out["net_force_over_largest_reaction"] = largest > 0.0 ? json(total.norm() / largest) : json(nullptr);
  // Energies of the final state: kinetic over strain energy near 0 means the body is at rest.
  const double strain = simulation.system().force_kernel().strain_energy(simulation.system().displacement());
  const double h = integrator.time_step;
  const double kinetic = simulation.system().last_step().kinetic_energy;
  out["strain_energy_J"] = strain;
  out["kinetic_energy_J"] = kinetic;
  out["kinetic_over_strain_energy"] = strain > 0.0 ? json(kinetic / strain) : json(nullptr);
  // The time step used against the stable estimate for the masses in use (mass-scaled under dynamic
  // relaxation); above 1 the monitors must catch a blow-up.
  const double stable = simulation.system().stable_time_step();
  out["time_step_over_stable"] = stable > 0.0 ? json(h / stable) : json(nullptr);
  if (integrator.relaxation) out["steady_state_relative_error_bound"] = integrator.relaxation->relative_error_bound;
  return out;
}

}  // namespace mtled
