#pragma once
// Reading a run's result back: the result file of a run folder, and the points and interpolated
// displacements of a result.vtu that mtled wrote (io/include/mtled/io/output.hpp writes them).
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "mtled/types.hpp"

namespace mtled {

// The result file of a run folder (folder/result.vtu) or the file itself; InputError naming the path when
// it does not exist (with the run's status from summary.json when the folder has one).
std::filesystem::path result_file_of(const std::filesystem::path& run);

struct ResultField {
  std::vector<Vec3> points;
  std::vector<Vec3> displacement;
  std::vector<std::array<Index, 4>> tets;  // the background tets
  std::string coordinate_system;  // "LPS" or "RAS" when the mesh recorded its frame (tag or summary.json), else empty
};
// InputError naming the file (and line) when it is not an mtled result.
ResultField read_result_vtu(const std::filesystem::path& file);

}  // namespace mtled
