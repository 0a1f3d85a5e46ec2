// Back to the image: mtled field writes a run's displacement on an image's grid as the displacement-field image 3D
// Slicer and ITK move images with (analysis/include/mtled/analysis/grid_field.hpp); mtled warp moves an image with it
// (analysis/include/mtled/analysis/image_warp.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "commands.hpp"
#include "mtled/analysis/grid_field.hpp"
#include "mtled/analysis/image_warp.hpp"
#include "mtled/analysis/result_file.hpp"
#include "mtled/errors.hpp"
#include "mtled/io/image.hpp"
#include "mtled/log.hpp"

namespace fs = std::filesystem;

namespace mtled::app {

namespace {

std::string result_frame(const ResultField& result, const std::string& frame_option, const fs::path& file) {
  const std::string& recorded = result.coordinate_system;
  if (!frame_option.empty()) {
    if (frame_option != "LPS" && frame_option != "RAS")
      throw InputError("--frame", fmt::format("\"{}\": LPS or RAS", frame_option));
    if (!recorded.empty() && recorded != frame_option)
      throw InputError("--frame", fmt::format("{} records its frame, {}; leave --frame out", file.string(), recorded));
    return frame_option;
  }
  if (recorded.empty())
    throw InputError(file.string(),
                     "the run's mesh records no patient frame (LPS or RAS), so where its points lie in the image is "
                     "not known: mesh the image itself (a label_map mesh source records it), or say the frame the "
                     "mesh's coordinates are in with --frame LPS or --frame RAS");
  return recorded;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct FieldRequest {
  fs::path run;
  const Image& image;  // gives the grid and its frame
  FieldDirection direction;
  std::string frame;  // --frame
  double decay_mm;
};

// The run's displacement on the image's grid, the vectors in the image's frame; the body must cover some voxel.
// The resampling field's X + u(X) = x is solved to a thousandth of a voxel: a point read that far off moves an
// interpolated value by a thousandth of the step between neighbouring voxels.
GridField field_on_image(const FieldRequest& request, const std::vector<fs::path>& plugin_paths) {
  PhaseLog phases;
  const fs::path file = result_file_of(request.run);
  const ResultField result = read_result_vtu(file);
  phases.lap("the run's result read");
  const std::string frame = result_frame(result, request.frame, file);
  const Image& image = request.image;
  if (image.space.empty())
    throw InputError(image.source,
                     "space: the image names no patient frame (LPS or RAS), so where the run's body lies "
                     "in it is not known; save it from 3D Slicer or another tool that writes \"space\"");
  // The grid in the result's frame; the vectors back in the image's.
  const Mat3 to_result = image.space == frame ? Mat3::Identity() : lps_ras_flip();
  VoxelGrid grid = image.grid;
  grid.axes = to_result * image.grid.axes;
  grid.origin = to_result * image.grid.origin;
  PluginCatalog catalog(plugin_search_path(plugin_paths, {}));
  GridField field = displacement_on_grid({result.points, result.tets, result.displacement}, grid, request.direction,
                                         catalog, 1e-3 * image.grid.spacing().minCoeff());
  phases.lap("the field inside the body");
  if (field.inside == 0)
    throw InputError(image.source, fmt::format("space origin / space directions: no voxel centre of the {}x{}x{} grid "
                                               "lies inside the run's body ({}): the image and the run do not overlap; "
                                               "check that the image is the one the scene was meshed from, in the "
                                               "same frame",
                                               grid.size[0], grid.size[1], grid.size[2], file.string()));
  for (Vec3& v : field.values) v = to_result * v;  // the flip is its own inverse
  if (request.decay_mm > 0.0) {
    const double decay = 1e-3 * request.decay_mm;
    const double largest = extend_outside(image.grid, decay, field);
    phases.lap("the field outside the body");
    if (decay < 1.5 * largest)
      log().warn(
          "--decay {} mm is under 1.5 times the largest displacement at the surface ({:.3g} mm): outside the "
          "body the extended map folds over itself; give --decay {:.0f} or more",
          request.decay_mm, 1e3 * largest, std::ceil(1.5e3 * largest));
  }
  if (request.direction == FieldDirection::resampling) {
    log().info("X + u(X) = x solved to {:.3g} m at worst; {} voxels not converged", field.largest_residual,
               field.not_converged);
    std::string named;
    const auto& n = image.grid.size;
    for (std::size_t k = 0; k < std::min<std::size_t>(5, field.not_converged_voxels.size()); ++k) {
      const std::int64_t v = field.not_converged_voxels[k];
      const Vec3 at = 1e3 * image.grid.centre(v % n[0], (v / n[0]) % n[1], v / (n[0] * n[1]));
      named += fmt::format("{}({}, {}, {}) at ({:.1f}, {:.1f}, {:.1f}) mm", k == 0 ? "" : ", ", v % n[0],
                           (v / n[0]) % n[1], v / (n[0] * n[1]), at[0], at[1], at[2]);
    }
    if (field.not_converged > 0)
      log().warn("not converged (the moved body folds there, or the field is too rough): voxel {}{} ({})", named,
                 field.not_converged > 5 ? ", ..." : "", image.space);
    if (field.overlapping > 0)
      log().warn(
          "{} voxels lie in more than one moved tet: the body folded there, and the field holds one of the "
          "reference points",
          field.overlapping);
  }
  return field;
}

void create_parent(const fs::path& file) {
  fs::create_directories(file.parent_path().empty() ? fs::path(".") : file.parent_path());
}

// The grid --origin, --spacing, --size and --space give, as an image of no values.
Image given_grid(const FieldOptions& options) {
  if (options.size.size() != 3)
    throw InputError("--like",
                     "give the image whose grid the field is sampled on (--like IMAGE), or the grid itself: "
                     "--origin X Y Z --spacing MM --size NX NY NZ --space LPS|RAS");
  Image image;
  image.source = "the grid given by --origin, --spacing, --size and --space";
  image.space = options.space;
  const std::vector<double>& s = options.spacing_mm;
  if (s.size() != 1 && s.size() != 3)
    throw InputError("--spacing", fmt::format("{} numbers: one (cubic voxels) or three (mm)", s.size()));
  image.grid.axes = 1e-3 * Vec3(s[0], s.size() == 3 ? s[1] : s[0], s.size() == 3 ? s[2] : s[0]).asDiagonal();
  image.grid.origin = 1e-3 * Vec3(options.origin_mm[0], options.origin_mm[1], options.origin_mm[2]);
  for (std::size_t a = 0; a < 3; ++a) image.grid.size[a] = options.size[a];
  if (image.grid.count() > (std::int64_t{1} << 31))
    throw InputError("--size", "more than 2^31 voxels: give a coarser grid or a smaller box");
  return image;
}

}  // namespace

int field_command(const FieldOptions& options, const std::vector<fs::path>& plugin_paths) {
  if (options.direction != "resampling" && options.direction != "forward")
    throw InputError("--direction", fmt::format("\"{}\": resampling (what Slicer and ITK resample with) or forward",
                                                options.direction));
  (void)is_nifti_name(options.output);  // a name of no image format fails before any work
  const auto start = std::chrono::steady_clock::now();
  PhaseLog phases;
  Image image = options.like.empty() ? given_grid(options) : read_image(options.like);
  phases.lap("the grid read");
  const FieldDirection direction =
      options.direction == "forward" ? FieldDirection::forward : FieldDirection::resampling;
  const GridField field =
      field_on_image({options.run, image, direction, options.frame, options.decay_mm}, plugin_paths);
  phases.lap("the field on the grid, all phases above");
  Image out;  // the grid and frame; the values are the field's own, three doubles a voxel
  out.grid = image.grid;
  out.space = image.space;
  out.components = 3;
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "a Vec3 is three doubles, unpadded");
  const std::span<const double> values(field.values.data()->data(), 3 * field.values.size());
  create_parent(options.output);
  // Slicer reads a NRRD field as a resampling transform unless it says otherwise.
  write_image(options.output, out, values,
              direction == FieldDirection::forward
                  ? std::map<std::string, std::string>{{"displacement field type", "modeling"}}
                  : std::map<std::string, std::string>{});
  phases.lap("the field written");
  log().info("{} displacement field on {}x{}x{} voxels of {}: {} inside the body, written to {} ({:.2f} s)",
             options.direction, image.grid.size[0], image.grid.size[1], image.grid.size[2], image.source, field.inside,
             options.output.string(), seconds_since(start));
  return 0;
}

int warp_command(const WarpOptions& options, const std::vector<fs::path>& plugin_paths) {
  if (!options.interpolation.empty() && options.interpolation != "linear" && options.interpolation != "nearest")
    throw InputError("--interpolation",
                     fmt::format("\"{}\": linear (intensities) or nearest (labels)", options.interpolation));
  (void)is_nifti_name(options.output);
  const auto start = std::chrono::steady_clock::now();
  const Image image = read_image(options.image);
  if (image.components != 1)
    throw InputError(options.image.string(),
                     "dimension / kinds: the image holds a vector per voxel (a displacement "
                     "field?); warp moves a scalar image: the MRI or the label map");
  const Interpolation interpolation = options.interpolation.empty()
                                          ? (image.whole_numbers() ? Interpolation::nearest : Interpolation::linear)
                                      : options.interpolation == "linear" ? Interpolation::linear
                                                                          : Interpolation::nearest;
  const GridField field =
      field_on_image({options.run, image, FieldDirection::resampling, options.frame, options.decay_mm}, plugin_paths);
  const Image warped = warp_image(image, field.values, interpolation);
  create_parent(options.output);
  write_image(options.output, warped);
  log().info(
      "{} warped into the deformed state of {} ({} interpolation, {}x{}x{} voxels, {} inside the body), "
      "written to {} ({:.2f} s)",
      options.image.string(), options.run.string(), interpolation == Interpolation::linear ? "linear" : "nearest",
      image.grid.size[0], image.grid.size[1], image.grid.size[2], field.inside, options.output.string(),
      seconds_since(start));
  return 0;
}

}  // namespace mtled::app
