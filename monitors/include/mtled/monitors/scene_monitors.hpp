#pragma once
// The checks a scene's "monitors" section asks for, added to a simulation's time loop: the energy monitor always,
// the stable-step re-estimate and the inversion check when their "every_steps" is not 0. Each check declares its own
// parameters beside its code; the kernel's loop only calls StepMonitor, and a program that needs none of them (a
// benchmark of the forces) leaves them out.
#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"

namespace mtled {

// The "monitors" section of a scene (validate_scene), declared by the checks.
SceneSection monitors_section();

void add_scene_monitors(Simulation& simulation, const Scene& scene);

}  // namespace mtled
