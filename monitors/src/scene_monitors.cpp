#include "mtled/monitors/scene_monitors.hpp"

#include <limits>

#include "energy_monitor.hpp"
#include "inversion_monitor.hpp"
#include "stable_step_monitor.hpp"

namespace mtled {

void add_scene_monitors(Simulation& simulation, const Scene& scene) {
  simulation.add_monitor(std::make_unique<EnergyMonitor>());
  if (const long every = scene.monitors.integer("stable_step_every_steps"); every > 0) {
    // 1e-7 of the body's size: far inside the linear range of any element, far above round-off in the forces.
    simulation.add_monitor(std::make_unique<StableStepMonitor>(
        every, static_cast<int>(scene.monitors.integer("stable_step_iterations")),
        1e-7 * simulation.model().length_scale(), scene.monitors.string("stable_step") == "adapt"));
  }
  if (const long every = scene.monitors.integer("inversion_every_steps"); every > 0)
    simulation.add_monitor(std::make_unique<InversionMonitor>(every, scene.monitors.string("inversion") == "stop"));
}

double monitored_kinetic_energy(const Simulation& simulation) {
  const auto* energy = dynamic_cast<const EnergyMonitor*>(simulation.monitor("energy"));
  return energy != nullptr ? energy->kinetic_energy() : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace mtled
