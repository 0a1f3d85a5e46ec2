#pragma once
// An image moved with the body: the reference (pre-operative) image resampled into the deformed configuration, as
// ITK's and 3D Slicer's resampling does. Each output voxel centre x reads the reference image at x + d(x), d the
// resampling displacement field on the same grid (grid_field.hpp): by trilinear interpolation for intensities, or the
// nearest voxel for labels. A point outside the reference image reads 0, as ITK's ResampleImageFilter does.
#include <span>

#include "mtled/io/image.hpp"

namespace mtled {

enum class Interpolation { linear, nearest };

// `reference` (scalar) moved by `resampling` (one vector per voxel of its grid, metres, in its frame). The output has
// the reference's grid, frame, stored type and key-value pairs.
Image warp_image(const Image& reference, std::span<const Vec3> resampling, Interpolation interpolation);

}  // namespace mtled
