#include "mtled/monitors/scene_monitors.hpp"

#include "energy_monitor.hpp"
#include "inversion_monitor.hpp"
#include "stable_step_monitor.hpp"

namespace mtled {

SceneSection monitors_section() {
  static const ComponentDeclaration declaration = [] {
    ComponentDeclaration d("monitors", Category::scene);
    d.summary(
        "Stability checks beyond the ones that are always on (non-finite values, J <= 0, energy growth): the "
        "time step against the stable step of the current, deformed body, adapted or stopped, and material "
        "folded between integration points (docs/stability.md).");
    StableStepMonitor::declare(d);
    InversionMonitor::declare(d);
    return d;
  }();
  return {"monitors", &declaration};
}

namespace {

// What the scene already does, so that a fold's message never advises it.
FoldAdvice fold_advice(const Scene& scene) {
  FoldAdvice advice;
  if (scene.needle) {
    const Parameters& needle = scene.needle->parameters;
    advice.needle_drives_nodes = needle.has("driven") && needle.string("driven") != "shaft_surface";
  }
  advice.refined_along = scene.mesh.parameters.has("refine_from");  // the Gmsh generators' refinement
  return advice;
}

}  // namespace

std::shared_ptr<const FoldedTets> add_scene_monitors(Simulation& simulation, const Scene& scene) {
  const Parameters& monitors = scene.section("monitors");
  simulation.add_monitor(std::make_unique<EnergyMonitor>());
  if (auto monitor = StableStepMonitor::from_section(monitors, simulation.model().view()))
    simulation.add_monitor(std::move(monitor));
  auto folded = std::make_shared<FoldedTets>();
  if (auto monitor = InversionMonitor::from_section(monitors, fold_advice(scene), folded))
    simulation.add_monitor(std::move(monitor));
  return folded;
}

}  // namespace mtled
