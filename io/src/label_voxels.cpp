#include "label_voxels.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "mtled/errors.hpp"

namespace mtled::label_voxels {

namespace {

template <class T>
T load(const char* p, bool swap) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if (swap) std::reverse(bytes, bytes + sizeof(T));
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

double value_at(const char* p, StoredType type, bool swap) {
  switch (type.kind) {
    case Kind::floating: return type.bytes == 4 ? load<float>(p, swap) : load<double>(p, swap);
    case Kind::signed_integer:
      switch (type.bytes) {
        case 1: return load<std::int8_t>(p, swap);
        case 2: return load<std::int16_t>(p, swap);
        case 4: return load<std::int32_t>(p, swap);
        default: return static_cast<double>(load<std::int64_t>(p, swap));
      }
    case Kind::unsigned_integer:
      switch (type.bytes) {
        case 1: return load<std::uint8_t>(p, swap);
        case 2: return load<std::uint16_t>(p, swap);
        case 4: return load<std::uint32_t>(p, swap);
        default: return static_cast<double>(load<std::uint64_t>(p, swap));
      }
  }
  return 0.0;
}

}  // namespace

std::vector<std::int32_t> decode(const char* data, std::int64_t count, StoredType type, bool swap,
                                 const std::string& source, const std::string& field) {
  std::vector<std::int32_t> labels(static_cast<std::size_t>(count));
  for (std::int64_t v = 0; v < count; ++v) {
    const double value = value_at(data + v * type.bytes, type, swap);
    if (!(std::floor(value) == value) || value < std::numeric_limits<std::int32_t>::min() ||
        value > std::numeric_limits<std::int32_t>::max())
      throw InputError(source, fmt::format("{}: voxel {} holds {}, not a label (labels are whole numbers that fit 32 "
                                           "bits): is this an intensity image rather than a label map?",
                                           field, v, value));
    labels[static_cast<std::size_t>(v)] = static_cast<std::int32_t>(value);
  }
  return labels;
}

void check_grid(const LabelImage& image, const std::string& field) {
  std::int64_t voxels = 1;
  for (const std::int64_t n : image.size) {
    if (n < 1 || n > (std::int64_t{1} << 31))
      throw InputError(image.source, fmt::format("sizes: {} voxels along an axis (allowed 1 to 2^31)", n));
    voxels *= n;
    if (voxels > (std::int64_t{1} << 31))
      throw InputError(image.source, "sizes: more than 2^31 voxels: crop or resample the label map first");
  }
  if (!image.origin.allFinite()) throw InputError(image.source, fmt::format("{}: the origin is not finite", field));
  const Vec3 spacing = image.spacing();
  if (!image.axes.allFinite() || !(spacing.minCoeff() > 0.0))
    throw InputError(image.source, fmt::format("{}: the voxel axes are singular (a zero or non-finite step along an "
                                               "index axis); the file's directions or spacings are broken",
                                               field));
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < a; ++b) {
      const double cosine = image.axes.col(a).dot(image.axes.col(b)) / (spacing[a] * spacing[b]);
      if (std::abs(cosine) > 1e-4)
        throw InputError(image.source, fmt::format("{}: the voxel axes {} and {} are not orthogonal (cosine {:.3g}): a "
                                                   "sheared grid is not supported; resample the image onto an "
                                                   "orthogonal grid (Slicer: Resample Scalar/Vector/DWI Volume)",
                                                   field, b, a, cosine));
    }
}

}  // namespace mtled::label_voxels
