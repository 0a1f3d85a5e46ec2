#pragma once
// What the NRRD and NIfTI readers share: voxel bytes of a stored type into values, and the checks of the grid's
// placement in space.
#include <cstdint>
#include <string>
#include <vector>

#include "mtled/io/image.hpp"

namespace mtled::image_voxels {

// `count` values of `type` from `data` (at least count * bytes long; byte order swapped when `swap`).
LargeVector<double> decode(const char* data, std::int64_t count, VoxelType type, bool swap);

// Checks the grid: positive sizes (at most 2^31 voxels in all), finite origin, axes not singular and orthogonal to
// 1e-4 (a sheared grid cannot be meshed as a rotated box); InputError naming `source` and `field`.
void check_grid(const VoxelGrid& grid, const std::string& source, const std::string& field);

}  // namespace mtled::image_voxels
