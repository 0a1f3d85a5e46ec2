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

// A regular grid placed in space: the centre of voxel (i, j, k) is origin + axes (i, j, k)^T (metres), the index i
// fastest in storage.
struct VoxelGrid {
  std::array<std::int64_t, 3> size{0, 0, 0};
  Mat3 axes = Mat3::Identity();
  Vec3 origin = Vec3::Zero();

  std::int64_t count() const { return size[0] * size[1] * size[2]; }
  std::int64_t index(std::int64_t i, std::int64_t j, std::int64_t k) const { return i + size[0] * (j + size[1] * k); }
  Vec3 centre(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return origin + axes * Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
  }
};

// `vectors` (metres, one per voxel, in the frame `space`, "LPS" or "RAS", the grid's too) as an attached-header
// NRRD file written under a temporary name and renamed when complete.
void write_nrrd_vectors(const std::filesystem::path& file, const VoxelGrid& grid, const std::string& space,
                        std::span<const Vec3> vectors);

// gzip (RFC 1952) of `bytes`, with no time stamp: the same bytes for the same input.
std::string gzip(const std::string& bytes);

}  // namespace mtled
