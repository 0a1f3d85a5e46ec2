#include "mtled/monitors/scene_monitors.hpp"

#include <fmt/format.h>

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

FoldAdvice fold_advice(const Scene& scene) {
  FoldAdvice advice;
  if (scene.needle) {
    const Parameters& needle = scene.needle->parameters;
    advice.needle_drives_nodes = needle.has("driven") && needle.string("driven") != "shaft_surface";
    advice.drag_limited = needle.has("drag_limit");
  }
  advice.refined_along = scene.mesh.parameters.has("refine_from");  // the mesh generators' refinement
  advice.refined_to_size = scene.mesh.parameters.has("refine_size");
  return advice;
}

std::string fold_advice_at(const Scene& scene, const NeedleStatus& needle, const Vec3& position) {
  const Vec3 x = position - needle.entry;
  const double axial = needle.direction.dot(x), radial = (x - axial * needle.direction).norm();
  if (needle.depth <= 0.0 || radial >= kBesideTheNeedle) return "";
  return fmt::format(
      "; at a needle depth of {:.1f} mm, {:.1f} mm from the needle's axis and {:.1f} mm under its "
      "entry: {}",
      1e3 * needle.depth, 1e3 * radial, 1e3 * axial, fold_lever(fold_advice(scene), &needle, radial, nullptr));
}

std::shared_ptr<const FoldedTets> add_scene_monitors(Simulation& simulation, const Scene& scene) {
  const Parameters& monitors = scene.section("monitors");
  simulation.loop().add_monitor(std::make_unique<EnergyMonitor>());
  if (auto monitor = StableStepMonitor::from_section(monitors, simulation.system().discretisation()))
    simulation.loop().add_monitor(std::move(monitor));
  auto folded = std::make_shared<FoldedTets>();
  if (auto monitor = InversionMonitor::from_section(monitors, fold_advice(scene), folded))
    simulation.loop().add_monitor(std::move(monitor));
  return folded;
}

}  // namespace mtled
