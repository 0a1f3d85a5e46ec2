#pragma once
// Writing images back for 3D Slicer and ITK: a displacement field (a 3-vector per voxel) as NRRD, the format
// Slicer saves grid transforms in ("kinds: vector domain domain domain"), in millimetres, float, gzip encoded.
#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

#include "mtled/types.hpp"

namespace mtled {

// Where the voxels of an image lie: the centre of voxel (i, j, k) is origin + axes (i, j, k)^T, in metres, in the
// patient frame `space` ("LPS" or "RAS").
struct ImagePlacement {
  std::array<std::int64_t, 3> size{0, 0, 0};
  Mat3 axes = Mat3::Identity();
  Vec3 origin = Vec3::Zero();
  std::string space = "LPS";
};

// `vectors` (metres, one per voxel, i fastest, in the placement's frame) as an attached-header NRRD file written
// under a temporary name and renamed when complete.
void write_nrrd_vectors(const std::filesystem::path& file, const ImagePlacement& placement,
                        std::span<const Vec3> vectors);

// gzip (RFC 1952) of `bytes`, with no time stamp: the same bytes for the same input.
std::string gzip(const std::string& bytes);

}  // namespace mtled
