#include "mtled/simulation.hpp"

#include "component_build.hpp"

namespace mtled {

// The integrator is built last, as before the split: a scene's setup errors come in the order of its sections' use.
Simulation::Simulation(const Scene& scene, PluginCatalog& catalog)
    : system_(scene, catalog), loop_(system_, build_component<TimeIntegrator>(catalog, scene.integrator)) {}

}  // namespace mtled
