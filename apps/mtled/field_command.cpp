// mtled field: a run's displacement sampled on an image's grid and written as a displacement-field image (NRRD), the
// transform 3D Slicer and ITK use to move an image (analysis/include/mtled/analysis/grid_field.hpp).
#include <fmt/format.h>

#include <chrono>

#include "commands.hpp"
#include "mtled/analysis/grid_field.hpp"
#include "mtled/analysis/result_file.hpp"
#include "mtled/errors.hpp"
#include "mtled/io/image_write.hpp"
#include "mtled/io/label_image.hpp"
#include "mtled/log.hpp"

namespace fs = std::filesystem;

namespace mtled::app {

namespace {

// LPS and RAS differ by the signs of x and y.
const Mat3 kFlip = Vec3(-1.0, -1.0, 1.0).asDiagonal();

std::string result_frame(const ResultField& result, const FieldOptions& options, const fs::path& file) {
  const std::string& recorded = result.coordinate_system;
  if (!options.frame.empty()) {
    if (options.frame != "LPS" && options.frame != "RAS")
      throw InputError("--frame", fmt::format("\"{}\": LPS or RAS", options.frame));
    if (!recorded.empty() && recorded != options.frame)
      throw InputError("--frame", fmt::format("{} records its frame, {}; leave --frame out", file.string(), recorded));
    return options.frame;
  }
  if (recorded.empty())
    throw InputError(file.string(),
                     "the run's mesh records no patient frame (LPS or RAS), so where its points lie in the image is "
                     "not known: mesh the image itself (a label_map mesh source records it), or say the frame the "
                     "mesh's coordinates are in with --frame LPS or --frame RAS");
  return recorded;
}

}  // namespace

int field_command(const FieldOptions& options, const std::vector<fs::path>& plugin_paths) {
  if (options.direction != "resampling" && options.direction != "forward")
    throw InputError("--direction", fmt::format("\"{}\": resampling (what Slicer and ITK resample with) or forward",
                                                options.direction));
  if (options.output.extension() != ".nrrd")
    throw InputError(options.output.string(), "the field is written as NRRD: name the file .nrrd");
  const auto start = std::chrono::steady_clock::now();
  const fs::path file = result_file_of(options.run);
  const ResultField result = read_result_vtu(file);
  const std::string frame = result_frame(result, options, file);
  const LabelImage image = read_label_image(options.like);
  // The grid in the result's frame; the vectors back in the image's.
  const Mat3 to_result = image.space == frame ? Mat3::Identity() : kFlip;
  VoxelGrid grid;
  grid.size = image.size;
  grid.axes = to_result * image.axes;
  grid.origin = to_result * image.origin;
  PluginCatalog catalog(plugin_search_path(plugin_paths, {}));
  GridField field = displacement_on_grid(
      {result.points, result.tets, result.displacement}, grid,
      options.direction == "forward" ? FieldDirection::forward : FieldDirection::resampling, catalog);
  for (Vec3& v : field.values) v = to_result * v;  // the flip is its own inverse
  fs::create_directories(options.output.parent_path().empty() ? fs::path(".") : options.output.parent_path());
  write_nrrd_vectors(options.output, {image.size, image.axes, image.origin}, image.space, field.values);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  log().info("{} displacement field on {}x{}x{} voxels of {}: {} inside the body, written to {} ({:.2f} s)",
             options.direction, image.size[0], image.size[1], image.size[2], options.like.string(), field.inside,
             options.output.string(), seconds);
  if (options.direction == "resampling") {
    log().info("X + u(X) = x solved to {:.3g} m at worst; {} voxels not converged", field.largest_residual,
               field.not_converged);
    if (field.overlapping > 0)
      log().warn(
          "{} voxels lie in more than one moved tet: the body folded there, and the field holds one of the "
          "reference points",
          field.overlapping);
  }
  return 0;
}

}  // namespace mtled::app
