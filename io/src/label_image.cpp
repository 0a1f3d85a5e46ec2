#include "mtled/io/label_image.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <limits>

#include "mtled/errors.hpp"

namespace fs = std::filesystem;

namespace mtled {

std::map<std::int32_t, std::int64_t> LabelImage::voxel_counts() const {
  std::map<std::int32_t, std::int64_t> counts;
  for (const std::int32_t label : labels) ++counts[label];
  return counts;
}

LabelImage to_label_image(const Image& image) {
  if (image.components != 1)
    throw InputError(image.source, "a label map holds one label per voxel; this image holds a vector per voxel (a "
                                   "displacement field?)");
  LabelImage out;
  out.size = image.grid.size;
  out.axes = image.grid.axes;
  out.origin = image.grid.origin;
  out.space = image.space;
  out.source = image.source;
  out.labels.resize(image.values.size());
  for (std::size_t v = 0; v < image.values.size(); ++v) {
    const double value = image.values[v];
    if (!(std::floor(value) == value) || value < std::numeric_limits<std::int32_t>::min() ||
        value > std::numeric_limits<std::int32_t>::max())
      throw InputError(image.source, fmt::format("the voxels: voxel {} holds {}, not a label (labels are whole numbers "
                                                 "that fit 32 bits): is this an intensity image rather than a label "
                                                 "map?", v, value));
    out.labels[v] = static_cast<std::int32_t>(value);
  }
  // Slicer's segmentation: SegmentN_Name and SegmentN_LabelValue (label N + 1 in files older than Slicer 4.11).
  for (int n = 0;; ++n) {
    const auto name = image.key_values.find(fmt::format("Segment{}_Name", n));
    if (name == image.key_values.end()) break;
    const auto value = image.key_values.find(fmt::format("Segment{}_LabelValue", n));
    const int label = value != image.key_values.end() ? std::atoi(value->second.c_str()) : n + 1;
    out.segment_names[label] = name->second;
  }
  return out;
}

LabelImage read_label_image(const fs::path& file) { return to_label_image(read_image(file)); }

}  // namespace mtled
