#pragma once
// A scene built into a running simulation: the mechanical system (mechanical_system.hpp) and the time loop that
// advances it with the scene's integrator (time_loop.hpp).
#include "mtled/mechanical_system.hpp"
#include "mtled/scene.hpp"
#include "mtled/time_loop.hpp"

namespace mtled {

class Simulation {
 public:
  // `bases`: MechanicalSystem's (null: the basis built for this run alone).
  Simulation(const Scene& scene, PluginCatalog& catalog, BasisCache* bases = nullptr);
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  MechanicalSystem& system() { return system_; }
  const MechanicalSystem& system() const { return system_; }
  TimeLoop& loop() { return loop_; }
  const TimeLoop& loop() const { return loop_; }

 private:
  MechanicalSystem system_;
  TimeLoop loop_;
};

}  // namespace mtled
