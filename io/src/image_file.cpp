// Images in and out: the file-name dispatch, gzip both ways, and the NRRD and NIfTI-1 writers (the readers are
// nrrd.cpp and nifti.cpp).
#include <fmt/format.h>
#include <zlib.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "mtled/errors.hpp"
#include "mtled/io/image.hpp"

namespace fs = std::filesystem;

namespace mtled {

namespace {

static_assert(std::endian::native == std::endian::little, "the headers written here say little endian");

template <class T>
void put(std::string& bytes, std::size_t offset, T value) {
  std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

// `value` in the stored type: whole types round and clamp to their range.
template <class T>
T stored(double value) {
  if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(value);
  } else {
    const double lowest = static_cast<double>(std::numeric_limits<T>::lowest());
    const double highest = static_cast<double>(std::numeric_limits<T>::max());
    return static_cast<T>(std::clamp(std::round(value), lowest, highest));
  }
}

template <class T>
void append_as(std::string& bytes, std::span<const double> values, double scale) {
  const std::size_t start = bytes.size();
  bytes.resize(start + values.size() * sizeof(T));
  for (std::size_t v = 0; v < values.size(); ++v) put(bytes, start + v * sizeof(T), stored<T>(scale * values[v]));
}

// `scale` times the values as the file stores them, `type` (native little-endian bytes).
std::string encode(std::span<const double> values, VoxelType type, double scale = 1.0) {
  std::string bytes;
  using K = VoxelKind;
  const auto is = [&](K kind, int size) { return type.kind == kind && type.bytes == size; };
  if (is(K::unsigned_integer, 1))
    append_as<std::uint8_t>(bytes, values, scale);
  else if (is(K::signed_integer, 1))
    append_as<std::int8_t>(bytes, values, scale);
  else if (is(K::signed_integer, 2))
    append_as<std::int16_t>(bytes, values, scale);
  else if (is(K::unsigned_integer, 2))
    append_as<std::uint16_t>(bytes, values, scale);
  else if (is(K::signed_integer, 4))
    append_as<std::int32_t>(bytes, values, scale);
  else if (is(K::unsigned_integer, 4))
    append_as<std::uint32_t>(bytes, values, scale);
  else if (is(K::signed_integer, 8))
    append_as<std::int64_t>(bytes, values, scale);
  else if (is(K::unsigned_integer, 8))
    append_as<std::uint64_t>(bytes, values, scale);
  else if (is(K::floating, 4))
    append_as<float>(bytes, values, scale);
  else
    append_as<double>(bytes, values, scale);
  return bytes;
}

std::string nrrd_type(VoxelType type) {
  switch (type.kind) {
    case VoxelKind::floating:
      return type.bytes == 4 ? "float" : "double";
    case VoxelKind::signed_integer:
      return type.bytes == 1 ? "signed char" : type.bytes == 2 ? "short" : type.bytes == 4 ? "int" : "long long int";
    case VoxelKind::unsigned_integer:
      return type.bytes == 1   ? "unsigned char"
             : type.bytes == 2 ? "unsigned short"
             : type.bytes == 4 ? "unsigned int"
                               : "unsigned long long int";
  }
  return "double";
}

// NIfTI's datatype code (nifti1.h: DT_UINT8 2, DT_INT16 4, DT_INT32 8, DT_FLOAT32 16, DT_FLOAT64 64, DT_INT8 256,
// DT_UINT16 512, DT_UINT32 768, DT_INT64 1024, DT_UINT64 1280).
std::int16_t nifti_datatype(VoxelType type) {
  switch (type.kind) {
    case VoxelKind::floating:
      return type.bytes == 4 ? 16 : 64;
    case VoxelKind::signed_integer:
      return type.bytes == 1 ? 256 : type.bytes == 2 ? 4 : type.bytes == 4 ? 8 : 1024;
    case VoxelKind::unsigned_integer:
      return type.bytes == 1 ? 2 : type.bytes == 2 ? 512 : type.bytes == 4 ? 768 : 1280;
  }
  return 64;
}

std::string vector_text(const Vec3& v) { return fmt::format("({:.17g},{:.17g},{:.17g})", v[0], v[1], v[2]); }

std::string nrrd_bytes(const Image& given, const std::map<std::string, std::string>& extra) {
  const bool vectors = given.components == 3;
  // A vector field goes in LPS whatever the grid's frame: ITK and Slicer turn a RAS grid to LPS on reading but leave
  // the vectors as stored.
  Image turned;
  if (vectors && given.space == "RAS") {
    turned = given;
    turned.space = "LPS";
    turned.grid.axes = lps_ras_flip() * given.grid.axes;
    turned.grid.origin = lps_ras_flip() * given.grid.origin;
    for (std::size_t v = 0; v < turned.values.size(); v += 3) {
      turned.values[v] = -turned.values[v];
      turned.values[v + 1] = -turned.values[v + 1];
    }
  }
  const Image& image = vectors && given.space == "RAS" ? turned : given;
  const VoxelType type = vectors ? VoxelType{VoxelKind::floating, 4} : image.type;
  const Mat3 axes_mm = 1e3 * image.grid.axes;
  std::string header =
      "NRRD0004\n# Complete NRRD file format specification at:\n"
      "# http://teem.sourceforge.net/nrrd/format.html\n";
  header += fmt::format("type: {}\ndimension: {}\n", nrrd_type(type), vectors ? 4 : 3);
  if (image.space == "RAS" || image.space == "LPS")
    header += fmt::format("space: {}\n", image.space == "RAS" ? "right-anterior-superior" : "left-posterior-superior");
  else
    header += "space dimension: 3\n";
  const auto& n = image.grid.size;
  header += fmt::format("sizes: {}{} {} {}\nspace directions: {}{} {} {}\nkinds: {}domain domain domain\n",
                        vectors ? "3 " : "", n[0], n[1], n[2], vectors ? "none " : "", vector_text(axes_mm.col(0)),
                        vector_text(axes_mm.col(1)), vector_text(axes_mm.col(2)), vectors ? "vector " : "");
  header += fmt::format("endian: little\nencoding: gzip\nspace origin: {}\nspace units: \"mm\" \"mm\" \"mm\"\n",
                        vector_text(1e3 * image.grid.origin));
  std::map<std::string, std::string> key_values = image.key_values;
  for (const auto& [key, value] : extra) key_values[key] = value;
  for (const auto& [key, value] : key_values) header += fmt::format("{}:={}\n", key, value);
  header += "\n";
  return header + gzip(encode(image.values, type, vectors ? 1e3 : 1.0));  // vectors in millimetres
}

// NIfTI-1 single file (the NIfTI-1 standard's nifti1.h layout): a 348-byte header, 4 bytes of no extension, the
// voxels from byte 352. The grid in RAS, placed by the sform and the same qform (as nibabel writes them); vectors
// as intent DISPVECT, dim[5] = 3, one component volume after another.
std::string nifti_bytes(const Image& image) {
  const bool vectors = image.components == 3;
  const VoxelType type = vectors ? VoxelType{VoxelKind::floating, 4} : image.type;
  const Mat3 to_ras = image.space == "LPS" ? lps_ras_flip() : Mat3::Identity();
  const Mat3 axes = 1e3 * to_ras * image.grid.axes;  // millimetres
  const Vec3 origin = 1e3 * to_ras * image.grid.origin;
  const Vec3 spacing = 1e3 * image.grid.spacing();
  std::string header(352, '\0');
  put<std::int32_t>(header, 0, 348);
  header[38] = 'r';
  const auto& n = image.grid.size;
  const std::int16_t dims[8] = {static_cast<std::int16_t>(vectors ? 5 : 3),
                                static_cast<std::int16_t>(n[0]),
                                static_cast<std::int16_t>(n[1]),
                                static_cast<std::int16_t>(n[2]),
                                1,
                                static_cast<std::int16_t>(vectors ? 3 : 1),
                                1,
                                1};
  for (std::size_t d = 0; d < 8; ++d) put(header, 40 + 2 * d, dims[d]);
  if (vectors) put<std::int16_t>(header, 68, 1006);  // NIFTI_INTENT_DISPVECT
  put<std::int16_t>(header, 70, nifti_datatype(type));
  put<std::int16_t>(header, 72, static_cast<std::int16_t>(8 * type.bytes));
  // The qform: a proper rotation and qfac = -1 when the axes are left-handed.
  Mat3 rotation = axes * spacing.cwiseInverse().asDiagonal();
  const float qfac = rotation.determinant() < 0.0 ? -1.0F : 1.0F;
  if (qfac < 0.0F) rotation.col(2) *= -1.0;
  Eigen::Quaterniond q(rotation);
  if (q.w() < 0.0) q.coeffs() *= -1.0;
  const float pixdim[8] = {
      qfac, static_cast<float>(spacing[0]), static_cast<float>(spacing[1]), static_cast<float>(spacing[2]), 0, 0, 0, 0};
  for (std::size_t d = 0; d < 8; ++d) put(header, 76 + 4 * d, pixdim[d]);
  put<float>(header, 108, 352.0F);    // vox_offset
  put<float>(header, 112, 1.0F);      // scl_slope: the values as they are
  header[123] = 2;                    // xyzt_units: millimetres
  put<std::int16_t>(header, 252, 1);  // qform_code: scanner
  put<std::int16_t>(header, 254, 1);  // sform_code: scanner
  const double quaternion[6] = {q.x(), q.y(), q.z(), origin[0], origin[1], origin[2]};
  for (std::size_t c = 0; c < 6; ++c) put(header, 256 + 4 * c, static_cast<float>(quaternion[c]));
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 4; ++c)
      put(header, 280 + 16 * r + 4 * c,
          static_cast<float>(c < 3 ? axes(static_cast<Index>(r), static_cast<Index>(c))
                                   : origin[static_cast<Index>(r)]));
  std::memcpy(header.data() + 344, "n+1", 4);
  if (!vectors) return header + encode(image.values, type);
  const auto voxels = static_cast<std::size_t>(image.grid.count());
  std::vector<double> planar(3 * voxels);
  for (std::size_t v = 0; v < voxels; ++v) {
    const Vec3 value = 1e3 * to_ras * Vec3(image.values[3 * v], image.values[3 * v + 1], image.values[3 * v + 2]);
    for (std::size_t c = 0; c < 3; ++c) planar[c * voxels + v] = value[static_cast<Index>(c)];
  }
  return header + encode(planar, type);
}

bool ends_with(const std::string& name, const std::string& suffix) {
  return name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void write_atomically(const fs::path& file, const std::string& bytes) {
  const fs::path temporary = file.parent_path() / ("." + file.filename().string() + ".tmp");
  {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw InputError(file.string(), "cannot write the image here: check the folder exists and is writable");
    out << bytes;
    if (!out.flush()) throw std::runtime_error(fmt::format("writing {} failed (disk full?)", file.string()));
  }
  fs::rename(temporary, file);
}

}  // namespace

std::string gzip(const std::string& bytes) {
  z_stream stream{};
  if (deflateInit2(&stream, Z_BEST_SPEED, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("zlib could not start deflating");
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  stream.avail_in = static_cast<uInt>(bytes.size());
  std::string out(deflateBound(&stream, static_cast<uLong>(bytes.size())), '\0');
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(out.size());
  const int status = deflate(&stream, Z_FINISH);
  out.resize(out.size() - stream.avail_out);
  deflateEnd(&stream);
  if (status != Z_STREAM_END) throw std::runtime_error("zlib could not finish deflating");
  return out;
}

std::string gunzip(const std::string& bytes, const std::string& source) {
  z_stream stream{};
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) throw std::runtime_error("zlib could not start inflating");
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  stream.avail_in = static_cast<uInt>(bytes.size());
  std::string out;
  char buffer[1 << 16];
  int status = Z_OK;
  while (status == Z_OK) {
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof buffer;
    status = inflate(&stream, Z_NO_FLUSH);
    out.append(buffer, sizeof buffer - stream.avail_out);
    if (status == Z_BUF_ERROR && stream.avail_in == 0) break;  // the stream ended early
  }
  inflateEnd(&stream);
  if (status != Z_STREAM_END)
    throw InputError(source, fmt::format("the gzip data is {} ({}); the file was cut short or is not gzip: save it "
                                         "again",
                                         status == Z_BUF_ERROR ? "truncated" : "corrupt",
                                         stream.msg != nullptr ? stream.msg : "zlib error"));
  return out;
}

bool is_nifti_name(const fs::path& file) {
  const std::string name = file.filename().string();
  if (ends_with(name, ".nii") || ends_with(name, ".nii.gz")) return true;
  if (ends_with(name, ".nrrd")) return false;
  throw InputError(file.string(),
                   "unknown image format: name the file .nrrd (or .seg.nrrd), .nii or .nii.gz (NRRD as "
                   "3D Slicer saves volumes, NIfTI as ITK-SNAP, FreeSurfer and nibabel do)");
}

Image read_image(const fs::path& file) {
  const bool nifti = is_nifti_name(file);
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw InputError(file.string(),
                     "cannot open the image: check the path (relative paths in a scene are taken from "
                     "the scene's folder)");
  std::ostringstream text;
  text << in.rdbuf();
  if (!nifti) return parse_nrrd(text.str(), file.string());
  if (ends_with(file.filename().string(), ".gz")) return parse_nifti(gunzip(text.str(), file.string()), file.string());
  return parse_nifti(text.str(), file.string());
}

void write_image(const fs::path& file, const Image& image, const std::map<std::string, std::string>& key_values) {
  if (image.components != 1 && image.components != 3)
    throw std::logic_error("write_image: an image holds a scalar or a 3-vector per voxel");
  if (!is_nifti_name(file)) {
    write_atomically(file, nrrd_bytes(image, key_values));
  } else {
    for (const std::int64_t n : image.grid.size)
      if (n > 32767)
        throw InputError(file.string(), fmt::format("{} voxels along an axis: NIfTI-1 holds at most 32767; write "
                                                    "NRRD (.nrrd) instead",
                                                    n));
    const std::string bytes = nifti_bytes(image);
    write_atomically(file, ends_with(file.filename().string(), ".gz") ? gzip(bytes) : bytes);
  }
}

}  // namespace mtled
