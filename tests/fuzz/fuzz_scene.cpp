// libFuzzer target: a scene's JSON text through parse_scene (syntax errors located by line and column, the
// line of every value recorded), `--set` overrides, and validate_scene against the build's real plugins
// (each loaded once, on the first input that names it). An InputError is the expected answer to a bad
// scene; anything else escaping, a sanitizer report or a hang is a finding.
//
// Input: the scene text, optionally followed by overrides, each on its own line after the marker
// "\n--set " (for example "...}\n--set /needle/depth=0.01"), as they would come from the command line.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "mtled/errors.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/analysis/scene_sections.hpp"
#include "mtled/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mtled;
  // The build tree's plugin folder only: the scene's own "plugin_paths" are not searched, so that an input
  // never makes the harness dlopen whatever it names.
  static PluginCatalog catalog([] {
    set_log_level("off");
    return std::vector<std::filesystem::path>{MTLED_FUZZ_PLUGIN_DIR};
  }());

  const std::string_view input(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view kMarker = "\n--set ";
  std::size_t end = input.find(kMarker);
  const std::string text(input.substr(0, end));
  std::vector<std::string> overrides;
  while (end != std::string_view::npos) {
    const std::size_t begin = end + kMarker.size();
    end = input.find(kMarker, begin);
    std::string_view assignment = input.substr(begin, end == std::string_view::npos ? end : end - begin);
    while (!assignment.empty() && (assignment.back() == '\n' || assignment.back() == '\r'))
      assignment.remove_suffix(1);  // an argument has no end of line
    overrides.emplace_back(assignment);
  }

  try {
    SceneDocument document = parse_scene(text, "fuzz.json", overrides);
    (void)scene_plugin_paths(document);
    (void)document.locate("/materials/0/mu");
    const Scene scene = validate_scene(std::move(document), catalog, run_scene_sections());
    (void)scene.section("output").string_list("cell_data");
  } catch (const InputError& e) {
    for (const auto& problem : e.problems()) (void)problem.format();  // as the command line prints them
  }
  return 0;
}
