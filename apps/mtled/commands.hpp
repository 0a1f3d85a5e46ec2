#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace mtled::app {

// Options every command that reads a scene shares.
struct SceneOptions {
  std::filesystem::path scene;
  std::vector<std::string> overrides;  // --set /pointer=value
  std::vector<std::filesystem::path> plugin_paths;
};

struct RunOptions {
  SceneOptions scene;
  std::filesystem::path output;
  int threads = 0;  // 0: all hardware threads
  bool progress = true;
};

// Each returns the process exit code (0 ok, 2 invalid input, 3 instability, 1 anything else); InputError
// and other exceptions propagate to main, which prints them and picks the code.
int run_scene(const RunOptions& options);
int validate_scene_command(const SceneOptions& options);
int list_plugins(const std::vector<std::filesystem::path>& plugin_paths, bool as_json, bool as_markdown,
                 const std::string& describe);
int print_schema(const std::vector<std::filesystem::path>& plugin_paths);

}  // namespace mtled::app
