#include "mtled/analysis/postprocess.hpp"

#include <algorithm>
#include <cmath>

#include "mtled/monitors/scene_monitors.hpp"

namespace mtled {

// Per-tet fields of result.vtu, averaged over each tet's integration points.
std::vector<CellField> cell_fields(const Model& model, std::span<const double> u, const std::vector<std::string>& names) {
  std::vector<CellField> fields;
  const auto tets = static_cast<std::size_t>(model.mesh().tet_count());
  for (const auto& name : names) {
    CellField field{name, name == "von_mises_stress" || name == "jacobian" ? 1 : 9, {}};
    field.values.assign(tets * static_cast<std::size_t>(field.components), 0.0);
    std::vector<int> count(tets, 0);
    for (Index ip = 0; ip < model.integration_point_count(); ++ip) {
      const Mat3 F = model.deformation_gradient(ip, u);
      const double J = F.determinant();
      Mat3 S = Mat3::Zero();
      model.ip_material(ip).stress(F, S);
      const Mat3 cauchy = F * S * F.transpose() / J;
      Mat3 value = Mat3::Zero();
      double scalar = 0.0;
      if (name == "green_strain") value = 0.5 * (F.transpose() * F - Mat3::Identity());
      if (name == "cauchy_stress") value = cauchy;
      if (name == "von_mises_stress") {
        const Mat3 deviator = cauchy - cauchy.trace() / 3.0 * Mat3::Identity();
        scalar = std::sqrt(1.5 * deviator.squaredNorm());
      }
      if (name == "jacobian") scalar = J;
      const auto t = static_cast<std::size_t>(model.ip_tets()[ip]);
      ++count[t];
      if (field.components == 1) {
        field.values[t] += scalar;
      } else {
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) field.values[9 * t + 3 * a + b] += value(a, b);
      }
    }
    for (std::size_t t = 0; t < tets; ++t)
      for (int c = 0; c < field.components; ++c) field.values[t * field.components + c] /= std::max(count[t], 1);
    fields.push_back(std::move(field));
  }
  return fields;
}

// The run's own error indicators, beside its timings (docs/studies.md): how far from equilibrium and from
// rest the final state is, and the time step against the stable one.
json error_indicators(Simulation& simulation) {
  const IntegratorReport integrator = simulation.integrator().report();
  json out = json::object();
  // Global equilibrium: every constraint reaction and external force together vanish at a steady state with
  // plain quadrature; consistent integration leaves a quadrature error that falls under refinement
  // (docs/studies.md). Measured against the largest reaction.
  Vec3 total = Vec3::Zero();
  double largest = 0.0;
  for (const auto* set : simulation.constraint_sets()) {
    total += set->total_reaction();
    for (const auto& r : set->reactions) largest = std::max(largest, r.norm());
  }
  if (simulation.has_external_forces()) {
    std::vector<double> f(simulation.displacement().size());
    simulation.external_forces(f);
    for (std::size_t i = 0; i < f.size(); ++i) total[static_cast<int>(i % 3)] += f[i];
  }
  out["net_force_N"] = json::array({total[0], total[1], total[2]});
  out["net_force_over_largest_reaction"] = largest > 0.0 ? json(total.norm() / largest) : json(nullptr);
  // Energies of the final state: kinetic over strain energy near 0 means the body is at rest.
  const Model& model = simulation.model();
  const double strain = model.strain_energy(simulation.displacement());
  const double h = integrator.time_step;
  const double kinetic = monitored_kinetic_energy(simulation);
  out["strain_energy_J"] = strain;
  out["kinetic_energy_J"] = std::isfinite(kinetic) ? json(kinetic) : json(nullptr);
  out["kinetic_over_strain_energy"] = strain > 0.0 && std::isfinite(kinetic) ? json(kinetic / strain) : json(nullptr);
  // The time step used against the stable estimate for the masses in use (mass-scaled under dynamic
  // relaxation); above 1 the monitors must catch a blow-up.
  const double stable = simulation.stable_time_step();
  out["time_step_over_stable"] = stable > 0.0 ? json(h / stable) : json(nullptr);
  if (integrator.relaxation) out["steady_state_relative_error_bound"] = integrator.relaxation->relative_error_bound;
  return out;
}

}  // namespace mtled
