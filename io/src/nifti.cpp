// NIfTI-1 and NIfTI-2 single-file images (.nii, and .nii.gz gunzipped by the caller): the 348- or 540-byte header,
// then the voxels at vox_offset: one 3-D volume of scalars, or of 3-vectors (dim[5] = 3, intent VECTOR or
// DISPVECT, stored one component volume after another). Placed by the sform when sform_code > 0, else by the qform
// when qform_code > 0, else by the voxel sizes alone (the standard's "method 1"); NIfTI's frame is RAS. Header
// layout: the NIfTI-1 and NIfTI-2 standards (nifti1.h, nifti2.h of the NIfTI Data Format Working Group).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "image_voxels.hpp"
#include "mtled/errors.hpp"
#include "mtled/io/image.hpp"

namespace mtled {

namespace {

using Kind = VoxelKind;

// Field offsets of the two header versions.
struct HeaderLayout {
  int version;
  std::size_t header_size, datatype, dim, pixdim, vox_offset, scl_slope, qform_code, sform_code, quatern, qoffset, srow,
      xyzt_units;
  bool wide;  // NIfTI-2: 64-bit dims, double reals, 32-bit codes
};
constexpr HeaderLayout kNifti1{1, 348, 70, 40, 76, 108, 112, 252, 254, 256, 268, 280, 123, false};
constexpr HeaderLayout kNifti2{2, 540, 12, 16, 104, 168, 176, 344, 348, 352, 376, 400, 500, true};

class HeaderReader {
 public:
  HeaderReader(const std::string& bytes, bool swap) : bytes_(bytes), swap_(swap) {}
  template <class T>
  T get(std::size_t offset) const {
    char raw[sizeof(T)];
    std::memcpy(raw, bytes_.data() + offset, sizeof(T));
    if (swap_) std::reverse(raw, raw + sizeof(T));
    T value;
    std::memcpy(&value, raw, sizeof(T));
    return value;
  }
  double real(const HeaderLayout& l, std::size_t offset) const {
    return l.wide ? get<double>(offset) : static_cast<double>(get<float>(offset));
  }
  std::int64_t integer(const HeaderLayout& l, std::size_t offset) const {  // dims and vox_offset
    return l.wide ? get<std::int64_t>(offset) : static_cast<std::int64_t>(get<std::int16_t>(offset));
  }
  int code(const HeaderLayout& l, std::size_t offset) const {
    return l.wide ? get<std::int32_t>(offset) : static_cast<int>(get<std::int16_t>(offset));
  }

 private:
  const std::string& bytes_;
  bool swap_;
};

VoxelType stored_type(int datatype, const std::string& source) {
  switch (datatype) {
    case 2: return {Kind::unsigned_integer, 1};
    case 4: return {Kind::signed_integer, 2};
    case 8: return {Kind::signed_integer, 4};
    case 16: return {Kind::floating, 4};
    case 64: return {Kind::floating, 8};
    case 256: return {Kind::signed_integer, 1};
    case 512: return {Kind::unsigned_integer, 2};
    case 768: return {Kind::unsigned_integer, 4};
    case 1024: return {Kind::signed_integer, 8};
    case 1280: return {Kind::unsigned_integer, 8};
    default:
      throw InputError(source, fmt::format("datatype: {} is not a scalar type an image can use (uint8, int16, "
                                           "int32, float32, ...)", datatype));
  }
}

// Metres per unit of the header's lengths (xyzt_units; millimetres when unknown, as the standard advises).
double length_unit(int xyzt_units) {
  switch (xyzt_units & 7) {
    case 1: return 1.0;
    case 3: return 1e-6;
    default: return 1e-3;
  }
}

// The standard's "method 2": the rotation of the quaternion (b, c, d), the voxel sizes, qfac and the offset.
void place_by_qform(VoxelGrid& grid, const HeaderReader& h, const HeaderLayout& l, const Vec3& spacing, double unit) {
  const double b = h.real(l, l.quatern), c = h.real(l, l.quatern + (l.wide ? 8 : 4)), d = h.real(l, l.quatern + (l.wide ? 16 : 8));
  const double a = std::sqrt(std::max(0.0, 1.0 - (b * b + c * c + d * d)));
  Mat3 rotation;
  rotation << a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c),  //
      2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b),           //
      2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - c * c - b * b;
  const double qfac = h.real(l, l.pixdim) < 0.0 ? -1.0 : 1.0;
  grid.axes = rotation * Vec3(spacing[0], spacing[1], qfac * spacing[2]).asDiagonal() * unit;
  const std::size_t step = l.wide ? 8 : 4;
  grid.origin = unit * Vec3(h.real(l, l.qoffset), h.real(l, l.qoffset + step), h.real(l, l.qoffset + 2 * step));
}

void place_by_sform(VoxelGrid& grid, const HeaderReader& h, const HeaderLayout& l, double unit) {
  const std::size_t step = l.wide ? 8 : 4;
  for (int r = 0; r < 3; ++r) {
    const std::size_t row = l.srow + static_cast<std::size_t>(r) * 4 * step;
    for (int c = 0; c < 3; ++c) grid.axes(r, c) = unit * h.real(l, row + static_cast<std::size_t>(c) * step);
    grid.origin[r] = unit * h.real(l, row + 3 * step);
  }
}

}  // namespace

Image parse_nifti(const std::string& bytes, const std::string& source) {
  if (bytes.size() < 4) throw InputError(source, "not a NIfTI file: shorter than its header");
  const std::int32_t native_size = HeaderReader(bytes, false).get<std::int32_t>(0);
  const bool swap = native_size != 348 && native_size != 540;
  const std::int32_t header_size = HeaderReader(bytes, swap).get<std::int32_t>(0);
  if (header_size != 348 && header_size != 540)
    throw InputError(source, "not a NIfTI file: sizeof_hdr is neither 348 (NIfTI-1) nor 540 (NIfTI-2)");
  const HeaderLayout& l = header_size == 348 ? kNifti1 : kNifti2;
  if (bytes.size() < l.header_size)
    throw InputError(source, fmt::format("the NIfTI-{} header is truncated: {} of {} bytes", l.version, bytes.size(),
                                         l.header_size));
  const HeaderReader h(bytes, swap);
  Image image;
  image.source = source;
  image.space = "RAS";
  VoxelGrid& grid = image.grid;
  const std::int64_t dims = h.integer(l, l.dim);
  if (dims < 3 || dims > 7)
    throw InputError(source, fmt::format("dim[0]: {} dimensions (an image has 3, a vector image 5)", dims));
  const std::size_t step = l.wide ? 8 : 2, real_step = l.wide ? 8 : 4;
  for (std::size_t a = 0; a < 3; ++a) grid.size[a] = h.integer(l, l.dim + (a + 1) * step);
  const auto dim = [&](std::size_t a) {
    return a < static_cast<std::size_t>(dims) ? h.integer(l, l.dim + (a + 1) * step) : 1;
  };
  if (dim(4) == 3) image.components = 3;  // dim[5]: the vector's components
  for (std::size_t a = 3; a < 7; ++a)
    if (dim(a) > 1 && !(a == 4 && image.components == 3))
      throw InputError(source, fmt::format("dim[{}]: {}; the image has more than one volume: an image here is one 3-D "
                                           "volume (or a vector one, dim[5] = 3)", a + 1, dim(a)));
  const Vec3 spacing(h.real(l, l.pixdim + real_step), h.real(l, l.pixdim + 2 * real_step),
                     h.real(l, l.pixdim + 3 * real_step));
  const double unit = length_unit(l.wide ? h.get<std::int32_t>(l.xyzt_units) : static_cast<int>(bytes[l.xyzt_units]));
  if (h.code(l, l.sform_code) > 0) {
    place_by_sform(grid, h, l, unit);
  } else if (h.code(l, l.qform_code) > 0) {
    place_by_qform(grid, h, l, spacing.cwiseAbs(), unit);
  } else {
    grid.axes = (unit * spacing.cwiseAbs()).asDiagonal();
  }
  image_voxels::check_grid(grid, source, h.code(l, l.sform_code) > 0 ? "srow_x/y/z (sform)" : "pixdim / quatern (qform)");
  const double slope = h.real(l, l.scl_slope), intercept = h.real(l, l.scl_slope + real_step);
  if (slope != 0.0 && (slope != 1.0 || intercept != 0.0))
    throw InputError(source, fmt::format("scl_slope {} and scl_inter {} rescale the voxels: store the values as they "
                                         "are (slope 0 or 1, intercept 0)", slope, intercept));
  const VoxelType type = stored_type(h.get<std::int16_t>(l.datatype), source);
  image.type = type;
  const double stored_offset = l.wide ? static_cast<double>(h.get<std::int64_t>(l.vox_offset)) : h.get<float>(l.vox_offset);
  if (!(stored_offset >= 0.0 && stored_offset <= static_cast<double>(bytes.size())))  // NaN too (found by fuzzing)
    throw InputError(source, fmt::format("vox_offset: {} is not a position in the file ({} bytes)", stored_offset,
                                         bytes.size()));
  const auto offset = static_cast<std::int64_t>(stored_offset);
  const std::int64_t count = grid.count() * image.components;
  if (offset < static_cast<std::int64_t>(l.header_size) || static_cast<std::size_t>(offset) > bytes.size() ||
      bytes.size() - static_cast<std::size_t>(offset) < static_cast<std::size_t>(count * type.bytes))
    throw InputError(source, fmt::format("the voxel data is truncated: {} values of {} bytes from vox_offset {} need "
                                         "{} bytes, the file has {}", count, type.bytes, offset,
                                         offset + count * type.bytes, bytes.size()));
  LargeVector<double> stored = image_voxels::decode(bytes.data() + offset, count, type, swap);
  if (image.components == 1) {
    image.values = std::move(stored);
    return image;
  }
  // One component volume after another in the file; components fastest here. Displacements are lengths.
  const auto voxels = static_cast<std::size_t>(grid.count());
  image.values.resize(stored.size());
  for (std::size_t c = 0; c < 3; ++c)
    for (std::size_t v = 0; v < voxels; ++v) image.values[3 * v + c] = unit * stored[c * voxels + v];
  return image;
}

}  // namespace mtled
