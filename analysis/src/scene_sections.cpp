#include "mtled/analysis/scene_sections.hpp"

#include "mtled/io/run_outputs.hpp"
#include "mtled/monitors/scene_monitors.hpp"

namespace mtled {

std::vector<SceneSection> run_scene_sections() { return {output_section(), monitors_section()}; }

}  // namespace mtled
