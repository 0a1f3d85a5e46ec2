#pragma once
// The monitors a scene asks for (its "monitors" section), added to a simulation's time loop: the energy
// monitor always, the stable-step re-estimate and the inversion check when their "every_steps" is not 0. The
// kernel's loop only calls StepMonitor; what each checks lives here, and a program that needs none of them
// (a benchmark of the forces) leaves them out.
#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"

namespace mtled {

void add_scene_monitors(Simulation& simulation, const Scene& scene);

// The kinetic energy at the last step as the energy monitor measures it (J): 1/2 v(n-1/2) . M v(n+1/2), the
// form central differences conserve (0 before the second step). NaN when the simulation has no energy monitor.
double monitored_kinetic_energy(const Simulation& simulation);

}  // namespace mtled
