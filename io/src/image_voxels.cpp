#include "image_voxels.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "mtled/errors.hpp"

namespace mtled::image_voxels {

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

double value_at(const char* p, VoxelType type, bool swap) {
  switch (type.kind) {
    case VoxelKind::floating: return type.bytes == 4 ? load<float>(p, swap) : load<double>(p, swap);
    case VoxelKind::signed_integer:
      switch (type.bytes) {
        case 1: return load<std::int8_t>(p, swap);
        case 2: return load<std::int16_t>(p, swap);
        case 4: return load<std::int32_t>(p, swap);
        default: return static_cast<double>(load<std::int64_t>(p, swap));
      }
    case VoxelKind::unsigned_integer:
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

LargeVector<double> decode(const char* data, std::int64_t count, VoxelType type, bool swap) {
  LargeVector<double> values(static_cast<std::size_t>(count));
#pragma omp parallel for schedule(static)
  for (std::int64_t v = 0; v < count; ++v)
    values[static_cast<std::size_t>(v)] = value_at(data + v * type.bytes, type, swap);
  return values;
}

void check_grid(const VoxelGrid& grid, const std::string& source, const std::string& field) {
  std::int64_t voxels = 1;
  for (const std::int64_t n : grid.size) {
    if (n < 1 || n > (std::int64_t{1} << 31))
      throw InputError(source, fmt::format("sizes: {} voxels along an axis (allowed 1 to 2^31)", n));
    voxels *= n;
    if (voxels > (std::int64_t{1} << 31))
      throw InputError(source, "sizes: more than 2^31 voxels: crop or resample the label map first");
  }
  if (!grid.origin.allFinite()) throw InputError(source, fmt::format("{}: the origin is not finite", field));
  const Vec3 spacing = grid.spacing();
  if (!grid.axes.allFinite() || !(spacing.minCoeff() > 0.0))
    throw InputError(source, fmt::format("{}: the voxel axes are singular (a zero or non-finite step along an "
                                               "index axis); the file's directions or spacings are broken",
                                               field));
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < a; ++b) {
      const double cosine = grid.axes.col(a).dot(grid.axes.col(b)) / (spacing[a] * spacing[b]);
      if (std::abs(cosine) > 1e-4)
        throw InputError(source, fmt::format("{}: the voxel axes {} and {} are not orthogonal (cosine {:.3g}): a "
                                                   "sheared grid is not supported; resample the image onto an "
                                                   "orthogonal grid (Slicer: Resample Scalar/Vector/DWI Volume)",
                                                   field, b, a, cosine));
    }
}

}  // namespace mtled::image_voxels
