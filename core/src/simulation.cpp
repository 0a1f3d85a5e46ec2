#include "mtled/simulation.hpp"

#include "component_build.hpp"

namespace mtled {

// The integrator is built last, after the system: a scene's setup errors come in the order its sections are used.
Simulation::Simulation(const Scene& scene, PluginCatalog& catalog, BasisCache* bases)
    : system_(scene, catalog, bases), loop_(system_, build_component<TimeIntegrator>(catalog, scene.integrator)) {}

}  // namespace mtled
