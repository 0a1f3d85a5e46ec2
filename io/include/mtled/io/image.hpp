#pragma once
// A medical image: values on a regular grid placed in physical space, as 3D Slicer (NRRD) and ITK-SNAP, FreeSurfer or
// nibabel (NIfTI-1/2) save them. A voxel holds a scalar (an intensity, a label) or a 3-vector (a displacement field).
// Read and written in NRRD (attached header, raw or gzip) and NIfTI (.nii, .nii.gz); every problem with a file is an
// InputError naming the file and the header field. The label maps the meshers read are these images with whole
// values (label_image.hpp).
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "mtled/io/large_buffer.hpp"
#include "mtled/types.hpp"

namespace mtled {

// A regular grid placed in space: the centre of voxel (i, j, k) is origin + axes (i, j, k)^T (metres), the index i
// fastest in storage. The columns of `axes` are the steps along the index axes: a rotation times the spacings.
struct VoxelGrid {
  std::array<std::int64_t, 3> size{0, 0, 0};
  Mat3 axes = Mat3::Identity();
  Vec3 origin = Vec3::Zero();

  std::int64_t count() const { return size[0] * size[1] * size[2]; }
  std::int64_t index(std::int64_t i, std::int64_t j, std::int64_t k) const { return i + size[0] * (j + size[1] * k); }
  Vec3 centre(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return origin + axes * Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
  }
  Vec3 spacing() const { return {axes.col(0).norm(), axes.col(1).norm(), axes.col(2).norm()}; }
};

// How a file stores each value.
enum class VoxelKind { signed_integer, unsigned_integer, floating };
struct VoxelType {
  VoxelKind kind = VoxelKind::unsigned_integer;
  int bytes = 1;
};

struct Image {
  VoxelGrid grid;
  int components = 1;          // 1: a scalar per voxel; 3: a vector (millimetres in the file, metres here)
  LargeVector<double> values;  // components fastest, then i, j, k
  VoxelType type;              // as stored; a warped image is written back in it
  std::string space;           // "RAS" or "LPS": the frame of the grid and of vector values; "" if the file has none
  std::map<std::string, std::string> key_values;  // NRRD "key:=value" pairs, kept on writing (Slicer's segments)
  std::string source;                             // the file, for messages

  bool whole_numbers() const { return type.kind != VoxelKind::floating; }
};

// Reads .nrrd / .seg.nrrd or .nii / .nii.gz, chosen by the file's name. Lengths (and vector values) in the file's
// unit, millimetres unless it says otherwise, become metres.
Image read_image(const std::filesystem::path& file);
Image parse_nrrd(const std::string& bytes, const std::string& source);
Image parse_nifti(const std::string& bytes, const std::string& source);

// Writes `image` as NRRD (.nrrd, gzip; scalars in their frame, vectors in LPS) or NIfTI-1 (.nii or .nii.gz; RAS),
// the grid and vector values turned to that frame where needed, under a temporary name renamed when complete. Scalars keep their stored type (rounded and
// clamped to it when whole); vectors are written as float millimetres: NRRD "kinds: vector domain domain domain",
// NIfTI intent DISPVECT (1006). `key_values` are added to the NRRD header.
void write_image(const std::filesystem::path& file, const Image& image,
                 const std::map<std::string, std::string>& key_values = {});
// The same with the values given apart (image.values is not read): a field written from where it was computed, with
// no copy of it laid out as an image first.
void write_image(const std::filesystem::path& file, const Image& image, std::span<const double> values,
                 const std::map<std::string, std::string>& key_values = {});

// The format a file name asks for: true for .nii / .nii.gz, false for .nrrd; an InputError for anything else.
bool is_nifti_name(const std::filesystem::path& file);

// LPS and RAS differ by the signs of x and y; the map is its own inverse.
inline Mat3 lps_ras_flip() { return Vec3(-1.0, -1.0, 1.0).asDiagonal(); }

// gzip (RFC 1952) of `bytes`, compressed fast (images are large: runs only, in pieces on every thread), with no time
// stamp: the same bytes for the same input on any number of threads.
std::string gzip(std::span<const char> bytes);
// The bytes, gunzipped (a truncated or corrupt stream is an InputError naming `source`).
std::string gunzip(const std::string& bytes, const std::string& source);

}  // namespace mtled
