#pragma once
// A segmented image: one integer label per voxel on a regular grid placed in physical space, as 3D Slicer
// (Segment Editor: .seg.nrrd, .nrrd), ITK-SNAP and FreeSurfer (.nii, .nii.gz) save label maps: an image (image.hpp)
// of whole scalar values, with Slicer's segment names and label values. Every problem is an InputError naming the
// file and the field.
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "mtled/io/image.hpp"
#include "mtled/types.hpp"

namespace mtled {

struct LabelImage {
  std::array<std::int64_t, 3> size{0, 0, 0};  // voxels along the three index axes
  std::vector<std::int32_t> labels;           // i fastest, then j, then k
  // Voxel (i, j, k) has its centre at origin + axes * (i, j, k): the columns of `axes` are the steps along the index
  // axes in physical space (m), orthogonal (a rotation times the spacings).
  Mat3 axes = Mat3::Identity();
  Vec3 origin = Vec3::Zero();
  std::string space;  // "RAS" or "LPS": the frame the physical coordinates are in
  std::map<std::int32_t, std::string> segment_names;  // label value -> segment name, where the file names them
  std::string source;  // the file, for messages

  std::int32_t at(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return labels[static_cast<std::size_t>(i + size[0] * (j + size[1] * k))];
  }
  Vec3 spacing() const { return {axes.col(0).norm(), axes.col(1).norm(), axes.col(2).norm()}; }
  Vec3 voxel_centre(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return origin + axes * Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
  }
  // Voxels per label value (0 included).
  std::map<std::int32_t, std::int64_t> voxel_counts() const;
};

// Reads .nrrd / .seg.nrrd (attached header) or .nii / .nii.gz, chosen by the file's name (read_image).
LabelImage read_label_image(const std::filesystem::path& file);
// The labels of a scalar image of whole numbers that fit 32 bits, else an InputError naming the image's file.
LabelImage to_label_image(const Image& image);

}  // namespace mtled
