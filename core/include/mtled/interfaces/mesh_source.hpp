#pragma once
#include <filesystem>

#include "mtled/mesh.hpp"
#include "mtled/parameters.hpp"

namespace mtled {

struct MeshContext {
  std::filesystem::path scene_directory;  // relative mesh paths are resolved against it
  int threads = 1;
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
