#pragma once
// The checks a scene's "monitors" section asks for, added to a simulation's time loop: the energy monitor always,
// the stable-step re-estimate and the inversion check when their "every_steps" is not 0. Each check declares its own
// parameters beside its code; the kernel's loop only calls StepMonitor, and a program that needs none of them (a
// benchmark of the forces) leaves them out.
#include <memory>
#include <vector>

#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"

namespace mtled {

// The "monitors" section of a scene (validate_scene), declared by the checks.
SceneSection monitors_section();

// The background tets the inversion check found turned inside out when it stopped a run, as a cell field for
// last_good_state.vtu ("folded": 1 folded away from the needle, 0.5 cut in the needle's zone, 0 whole); empty
// until such a check, or when the scene turns the check off.
struct FoldedTets {
  std::vector<double> per_tet;
};

// Adds the checks; returns what the inversion check marks when it stops a run.
std::shared_ptr<const FoldedTets> add_scene_monitors(Simulation& simulation, const Scene& scene);

// For an inverted material point at `position` within 20 mm of the needle's axis: where it is against the needle and
// the lever the scene can still pull ("; at a needle depth of ...: ..."); empty farther away or before the needle
// went in.
std::string fold_advice_at(const Scene& scene, const NeedleStatus& needle, const Vec3& position);

}  // namespace mtled
