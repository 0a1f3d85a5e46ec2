#include "mtled/analysis/result_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>

#include "mtled/errors.hpp"
#include "mtled/io/vtk_grid.hpp"
#include "mtled/json.hpp"
#include "study_support.hpp"

namespace fs = std::filesystem;

namespace mtled {

fs::path result_file_of(const fs::path& run) {
  std::error_code ec;
  if (!fs::exists(run, ec)) throw InputError(run.string(), "no such run folder or result file");
  if (!fs::is_directory(run, ec)) return run;
  const fs::path file = run / "result.vtu";
  if (fs::exists(file, ec)) return file;
  const json summary = study::read_json_file(run / "summary.json");
  const std::string status = summary.is_object() ? summary.value("status", "") : "";
  throw InputError(file.string(), status.empty() || status == "ok"
                                      ? "missing: not an mtled run folder, or its run did not finish"
                                      : fmt::format("missing: the run's summary.json says status \"{}\", so it wrote "
                                                    "no result",
                                                    status));
}

ResultField read_result_vtu(const fs::path& file) {
  // The VTK reader of the vtk_file mesh plugin, so that every form a result may be in (mtled's binary or
  // ASCII, or a file re-saved by ParaView) reads.
  const mesh_readers::MeshFileText text = mesh_readers::read_text_file(file, file.string());
  vtk::ArrayRequest request;
  request.point_arrays = {"displacement"};
  const vtk::UnstructuredGrid grid = vtk::read_vtu(text, request);
  const auto displacement = std::find_if(grid.point_arrays.begin(), grid.point_arrays.end(),
                                         [](const vtk::DataArray& a) { return a.name == "displacement"; });
  if (displacement == grid.point_arrays.end() || displacement->components != 3 ||
      displacement->values.size() != 3 * grid.points.size())
    throw InputError(file.string(), "not an mtled result: no point array \"displacement\" of 3 components per point");
  // Back to metres from a result written in millimetres (/output/length_unit).
  const double to_metres = vtk::metres_per_length_unit(grid, file.string());
  ResultField result;
  for (const Vec3& p : grid.points) result.points.push_back(p * to_metres);
  result.tets = grid.tets;
  // The frame: the file's SPACE tag (RAS), else what the run's summary.json beside it recorded of its mesh.
  result.coordinate_system = grid.coordinate_system;
  if (result.coordinate_system.empty()) {
    const json summary = study::read_json_file(file.parent_path() / "summary.json");
    if (summary.is_object())
      result.coordinate_system = summary.value("/mesh/coordinate_system"_json_pointer, std::string());
  }
  for (std::size_t i = 0; i < grid.points.size(); ++i)
    result.displacement.push_back(to_metres * Vec3{displacement->values[3 * i], displacement->values[3 * i + 1],
                                                   displacement->values[3 * i + 2]});
  return result;
}

}  // namespace mtled
