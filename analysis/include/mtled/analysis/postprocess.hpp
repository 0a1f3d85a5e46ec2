#pragma once
// Quantities derived from a run's state for its outputs, each defined once here (the command line only asks
// for them): the per-tet fields of result.vtu, and the run's own error indicators in summary.json.
#include <span>
#include <string>
#include <vector>

#include "mtled/json.hpp"
#include "mtled/model.hpp"
#include "mtled/io/output.hpp"
#include "mtled/simulation.hpp"

namespace mtled {

// Per-tet fields of result.vtu, each averaged over the tet's integration points: "green_strain" and
// "cauchy_stress" (9 components, row-major), "von_mises_stress" and "jacobian" (1) (the scene's
// /output/cell_data choices).
std::vector<CellField> cell_fields(const Model& model, std::span<const double> u, const std::vector<std::string>& names);

// The final state's distance from equilibrium and from rest, and the time step against the stable one
// (docs/studies.md): net_force_N, net_force_over_largest_reaction, strain_energy_J, kinetic_energy_J (the
// energy monitor's, monitored_kinetic_energy), kinetic_over_strain_energy, time_step_over_stable and, for a
// steady-state integrator, steady_state_relative_error_bound.
json error_indicators(Simulation& simulation);

}  // namespace mtled
