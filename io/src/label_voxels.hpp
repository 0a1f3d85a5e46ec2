#pragma once
// What the NRRD and NIfTI readers share: voxel bytes of a stored type into int32 labels, and the checks of the
// grid's placement in space.
#include <cstdint>
#include <string>
#include <vector>

#include "mtled/io/label_image.hpp"

namespace mtled::label_voxels {

enum class Kind { signed_integer, unsigned_integer, floating };

struct StoredType {
  Kind kind = Kind::unsigned_integer;
  int bytes = 1;
};

// `count` voxels of `type` from `data` (at least count * bytes long; byte order swapped when `swap`), as labels.
// A value that is not a whole number or does not fit an int32 is an InputError naming `source` and `field`.
std::vector<std::int32_t> decode(const char* data, std::int64_t count, StoredType type, bool swap,
                                 const std::string& source, const std::string& field);

// Checks the grid: positive sizes (at most 2^31 voxels in all), finite origin, axes not singular and orthogonal to
// 1e-4 (a sheared grid cannot be meshed as a rotated box); InputError naming `source` and `field`.
void check_grid(const LabelImage& image, const std::string& field);

}  // namespace mtled::label_voxels
