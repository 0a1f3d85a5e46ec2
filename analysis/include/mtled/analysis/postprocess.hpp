#pragma once
// The run's own error indicators in summary.json, derived from its final state (the per-tet fields of result.vtu
// are mtled/io/derived_fields.hpp).
#include <span>
#include <string>
#include <vector>

#include "mtled/json.hpp"
#include "mtled/simulation.hpp"

namespace mtled {

// The final state's distance from equilibrium and from rest, and the time step against the stable one
// (docs/studies.md): net_force_N, net_force_over_largest_reaction, strain_energy_J, kinetic_energy_J
// (StepRecord::kinetic_energy), kinetic_over_strain_energy, time_step_over_stable and, for a
// steady-state integrator, steady_state_relative_error_bound.
json error_indicators(Simulation& simulation);

}  // namespace mtled
