#include "mtled/analysis/image_warp.hpp"

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

namespace mtled {

namespace {

double voxel_value(const Image& image, std::int64_t i, std::int64_t j, std::int64_t k) {
  const auto& n = image.grid.size;
  if (i < 0 || j < 0 || k < 0 || i >= n[0] || j >= n[1] || k >= n[2]) return 0.0;
  return image.values[static_cast<std::size_t>(image.grid.index(i, j, k))];
}

// The reference image at continuous index q (voxel centres at whole numbers).
double sample(const Image& image, const Vec3& q, Interpolation interpolation) {
  if (interpolation == Interpolation::nearest)
    return voxel_value(image, std::llround(q[0]), std::llround(q[1]), std::llround(q[2]));
  const Vec3 base = q.array().floor();
  const Vec3 w = q - base;
  const auto i = static_cast<std::int64_t>(base[0]), j = static_cast<std::int64_t>(base[1]),
             k = static_cast<std::int64_t>(base[2]);
  double value = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int a = c & 1, b = (c >> 1) & 1, d = (c >> 2) & 1;
    const double weight = (a ? w[0] : 1.0 - w[0]) * (b ? w[1] : 1.0 - w[1]) * (d ? w[2] : 1.0 - w[2]);
    if (weight != 0.0) value += weight * voxel_value(image, i + a, j + b, k + d);
  }
  return value;
}

}  // namespace

Image warp_image(const Image& reference, std::span<const Vec3> resampling, Interpolation interpolation) {
  if (reference.components != 1) throw std::logic_error("warp_image: a scalar image");
  if (static_cast<std::int64_t>(resampling.size()) != reference.grid.count())
    throw std::logic_error("warp_image: one displacement per voxel");
  Image out = reference;
  const VoxelGrid& grid = reference.grid;
  const Mat3 to_index = grid.axes.inverse();
#pragma omp parallel for schedule(static)
  for (std::int64_t k = 0; k < grid.size[2]; ++k)
    for (std::int64_t j = 0; j < grid.size[1]; ++j)
      for (std::int64_t i = 0; i < grid.size[0]; ++i) {
        const auto v = static_cast<std::size_t>(grid.index(i, j, k));
        if (resampling[v].isZero(0.0)) continue;  // not moved: the value is already there
        const Vec3 q =
            Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)) + to_index * resampling[v];
        out.values[v] = sample(reference, q, interpolation);
      }
  return out;
}

}  // namespace mtled
