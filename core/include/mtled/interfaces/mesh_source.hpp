#pragma once
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "mtled/mesh.hpp"
#include "mtled/parameters.hpp"

namespace mtled {

// The straight path a scene's needle is planned to sweep, from its entry to its tip at the final depth, known from
// the needle's parameters before any mesh exists. `frame`: "LPS" or "RAS" when it came from a 3D Slicer markups file,
// empty when the scene gave it in the mesh's own coordinates.
struct PlannedPath {
  Vec3 entry = Vec3::Zero(), tip = Vec3::Zero();
  std::string frame;

  bool operator==(const PlannedPath& other) const {
    return entry == other.entry && tip == other.tip && frame == other.frame;
  }
};

struct MeshContext {
  std::filesystem::path scene_directory;  // relative mesh paths are resolved against it
  int threads = 1;
  // The scene's needle's planned path, for a mesh refined along it (refine_along_needle): builds the needle from its
  // section when called, so a scene that does not ask loads no needle. Empty, or returning none, when the scene has no
  // needle or its model plans no straight path.
  std::function<std::optional<PlannedPath>()> needle_path;
};

// Produces the tetrahedral mesh a scene is built on: a file reader or a generator.
class MeshSource {
 public:
  static constexpr Category category = Category::mesh;
  virtual ~MeshSource();
  // Throws InputError naming the file (and line) or the scene pointer when the input is unusable.
  virtual TetMesh load(const MeshContext& context) = 0;
};

}  // namespace mtled
