#pragma once
// The sections of a scene that `mtled run` reads beside the kernel's own: "output" (declared by the writers in io/)
// and "monitors" (declared by the checks in monitors/). Whatever validates a scene for a run passes these.
#include <vector>

#include "mtled/scene.hpp"

namespace mtled {

std::vector<SceneSection> run_scene_sections();

}  // namespace mtled
