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
#include <memory>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "mtled/errors.hpp"
#include "mtled/io/image.hpp"

namespace fs = std::filesystem;

namespace mtled {

namespace {

// A gzip stream (gzip() below) kept in parts, header, pieces and trailer, to be written one after another.
class GzipParts {
 public:
  explicit GzipParts(std::span<const char> bytes);
  std::vector<std::span<const char>> parts() const;

 private:
  std::string header_, trailer_;
  std::vector<std::unique_ptr<char[]>> pieces_;
  std::vector<std::size_t> sizes_;
};

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

// Appends the values as the file stores them, `type` (native little-endian bytes): value i (component i % components)
// times scale[i % components]; `planar` puts one component's volume after another (NIfTI) instead of components
// fastest.
struct Layout {
  int components = 1;
  Vec3 scale = Vec3::Ones();
  bool planar = false;
};

template <class T>
void append_as(LargeVector<char>& bytes, std::span<const double> values, const Layout& layout) {
  const std::size_t start = bytes.size();
  bytes.resize(start + values.size() * sizeof(T));
  char* out = bytes.data() + start;
  const auto components = static_cast<std::size_t>(layout.components);
  const std::size_t voxels = values.size() / components;
#pragma omp parallel for schedule(static)
  for (std::size_t o = 0; o < values.size(); ++o) {
    const std::size_t c = layout.planar ? o / voxels : o % components;
    const std::size_t in = layout.planar ? components * (o % voxels) + c : o;
    const T value = stored<T>(layout.scale[static_cast<Index>(c)] * values[in]);
    std::memcpy(out + o * sizeof(T), &value, sizeof(T));
  }
}

void append_encoded(LargeVector<char>& bytes, std::span<const double> values, VoxelType type, const Layout& layout) {
  using K = VoxelKind;
  const auto is = [&](K kind, int size) { return type.kind == kind && type.bytes == size; };
  if (is(K::unsigned_integer, 1))
    append_as<std::uint8_t>(bytes, values, layout);
  else if (is(K::signed_integer, 1))
    append_as<std::int8_t>(bytes, values, layout);
  else if (is(K::signed_integer, 2))
    append_as<std::int16_t>(bytes, values, layout);
  else if (is(K::unsigned_integer, 2))
    append_as<std::uint16_t>(bytes, values, layout);
  else if (is(K::signed_integer, 4))
    append_as<std::int32_t>(bytes, values, layout);
  else if (is(K::unsigned_integer, 4))
    append_as<std::uint32_t>(bytes, values, layout);
  else if (is(K::signed_integer, 8))
    append_as<std::int64_t>(bytes, values, layout);
  else if (is(K::unsigned_integer, 8))
    append_as<std::uint64_t>(bytes, values, layout);
  else if (is(K::floating, 4))
    append_as<float>(bytes, values, layout);
  else
    append_as<double>(bytes, values, layout);
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

// The NRRD header and the gzipped voxels.
std::pair<std::string, GzipParts> nrrd_bytes(const Image& image, std::span<const double> values,
                                             const std::map<std::string, std::string>& extra) {
  const bool vectors = image.components == 3;
  // A vector field goes in LPS whatever the grid's frame: ITK and Slicer turn a RAS grid to LPS on reading but leave
  // the vectors as stored.
  const bool to_lps = vectors && image.space == "RAS";
  const Mat3 turn = to_lps ? lps_ras_flip() : Mat3::Identity();
  const std::string space = to_lps ? "LPS" : image.space;
  const VoxelType type = vectors ? VoxelType{VoxelKind::floating, 4} : image.type;
  const Mat3 axes_mm = 1e3 * turn * image.grid.axes;
  std::string header =
      "NRRD0004\n# Complete NRRD file format specification at:\n"
      "# http://teem.sourceforge.net/nrrd/format.html\n";
  header += fmt::format("type: {}\ndimension: {}\n", nrrd_type(type), vectors ? 4 : 3);
  if (space == "RAS" || space == "LPS")
    header += fmt::format("space: {}\n", space == "RAS" ? "right-anterior-superior" : "left-posterior-superior");
  else
    header += "space dimension: 3\n";
  const auto& n = image.grid.size;
  header += fmt::format("sizes: {}{} {} {}\nspace directions: {}{} {} {}\nkinds: {}domain domain domain\n",
                        vectors ? "3 " : "", n[0], n[1], n[2], vectors ? "none " : "", vector_text(axes_mm.col(0)),
                        vector_text(axes_mm.col(1)), vector_text(axes_mm.col(2)), vectors ? "vector " : "");
  header += fmt::format("endian: little\nencoding: gzip\nspace origin: {}\nspace units: \"mm\" \"mm\" \"mm\"\n",
                        vector_text(1e3 * turn * image.grid.origin));
  std::map<std::string, std::string> key_values = image.key_values;
  for (const auto& [key, value] : extra) key_values[key] = value;
  for (const auto& [key, value] : key_values) header += fmt::format("{}:={}\n", key, value);
  header += "\n";
  LargeVector<char> voxels;
  // Vectors in millimetres.
  append_encoded(voxels, values, type, vectors ? Layout{3, 1e3 * turn.diagonal(), false} : Layout{});
  return {std::move(header), GzipParts(voxels)};
}

// NIfTI-1 single file (the NIfTI-1 standard's nifti1.h layout): a 348-byte header, 4 bytes of no extension, the
// voxels from byte 352. The grid in RAS, placed by the sform and the same qform (as nibabel writes them); vectors
// as intent DISPVECT, dim[5] = 3, one component volume after another.
LargeVector<char> nifti_bytes(const Image& image, std::span<const double> values) {
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
  LargeVector<char> bytes(header.begin(), header.end());
  append_encoded(bytes, values, type, vectors ? Layout{3, 1e3 * to_ras.diagonal(), true} : Layout{});
  return bytes;
}

bool ends_with(const std::string& name, const std::string& suffix) {
  return name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void write_atomically(const fs::path& file, const std::vector<std::span<const char>>& parts) {
  const fs::path temporary = file.parent_path() / ("." + file.filename().string() + ".tmp");
  {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw InputError(file.string(), "cannot write the image here: check the folder exists and is writable");
    for (const std::span<const char> part : parts) out.write(part.data(), static_cast<std::streamsize>(part.size()));
    if (!out.flush()) throw std::runtime_error(fmt::format("writing {} failed (disk full?)", file.string()));
  }
  fs::rename(temporary, file);
}

}  // namespace

// One gzip member written by threads: the data cut into 1 MiB pieces, each deflated on its own (raw deflate, ended by
// a sync flush so the next piece starts on a byte; the last one finishes the stream) and their CRC-32s combined, as
// pigz does. Any gzip reader reads it as one stream; each piece starts with an empty dictionary, which costs a
// fraction of a percent in size. Matches are runs only (zlib's Z_RLE): on a displacement field (zeros outside, float
// noise inside) as small as zlib's fastest level and twice as fast, on a label map half the size. The parts (header,
// pieces, trailer) are kept apart, to be written one after the other without joining them first.
GzipParts::GzipParts(std::span<const char> bytes) {
  constexpr std::size_t kPiece = std::size_t{1} << 20;
  const std::size_t pieces = std::max<std::size_t>(1, (bytes.size() + kPiece - 1) / kPiece);
  pieces_.resize(pieces);
  sizes_.assign(pieces, 0);
  std::vector<uLong> crc(pieces);
  bool failed = false;
#pragma omp parallel for schedule(dynamic) reduction(|| : failed)
  for (std::size_t p = 0; p < pieces; ++p) {
    const std::size_t first = p * kPiece, size = std::min(kPiece, bytes.size() - std::min(bytes.size(), first));
    const auto* data = reinterpret_cast<const Bytef*>(bytes.data() + first);
    crc[p] = crc32(crc32(0L, Z_NULL, 0), data, static_cast<uInt>(size));
    z_stream stream{};
    if (deflateInit2(&stream, Z_BEST_SPEED, Z_DEFLATED, -MAX_WBITS, 8, Z_RLE) != Z_OK) {
      failed = true;
      continue;
    }
    const std::size_t room = deflateBound(&stream, static_cast<uLong>(size)) + 16;  // + the sync flush's empty block
    pieces_[p].reset(new char[room]);  // not zeroed: deflate writes what is kept
    stream.next_in = const_cast<Bytef*>(data);
    stream.avail_in = static_cast<uInt>(size);
    stream.next_out = reinterpret_cast<Bytef*>(pieces_[p].get());
    stream.avail_out = static_cast<uInt>(room);
    const bool last = p + 1 == pieces;
    const int status = deflate(&stream, last ? Z_FINISH : Z_SYNC_FLUSH);
    failed = failed || (last ? status != Z_STREAM_END : status != Z_OK || stream.avail_in != 0);
    sizes_[p] = room - stream.avail_out;
    deflateEnd(&stream);
  }
  if (failed) throw std::runtime_error("zlib could not deflate the image");
  uLong total_crc = crc[0];
  for (std::size_t p = 1; p < pieces; ++p)
    total_crc = crc32_combine(total_crc, crc[p], static_cast<z_off_t>(std::min(kPiece, bytes.size() - p * kPiece)));
  header_.assign("\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\xff", 10);  // gzip, deflate, no flags or time, unknown OS
  const auto little_endian = [&](std::uint32_t value) {
    for (int b = 0; b < 4; ++b) trailer_.push_back(static_cast<char>((value >> (8 * b)) & 0xffu));
  };
  little_endian(static_cast<std::uint32_t>(total_crc));
  little_endian(static_cast<std::uint32_t>(bytes.size() & 0xffffffffu));  // ISIZE: the length modulo 2^32
}

std::vector<std::span<const char>> GzipParts::parts() const {
  std::vector<std::span<const char>> out{header_};
  for (std::size_t p = 0; p < pieces_.size(); ++p) out.emplace_back(pieces_[p].get(), sizes_[p]);
  out.emplace_back(trailer_);
  return out;
}

std::string gzip(std::span<const char> bytes) {
  std::string out;
  for (const std::span<const char> part : GzipParts(bytes).parts()) out.append(part.data(), part.size());
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
  write_image(file, image, image.values, key_values);
}

void write_image(const fs::path& file, const Image& image, std::span<const double> values,
                 const std::map<std::string, std::string>& key_values) {
  if (image.components != 1 && image.components != 3)
    throw std::logic_error("write_image: an image holds a scalar or a 3-vector per voxel");
  if (values.size() != static_cast<std::size_t>(image.components * image.grid.count()))
    throw std::logic_error("write_image: the values do not fill the grid");
  if (!is_nifti_name(file)) {
    const auto [header, voxels] = nrrd_bytes(image, values, key_values);
    std::vector<std::span<const char>> parts = voxels.parts();
    parts.insert(parts.begin(), header);
    write_atomically(file, parts);
  } else {
    for (const std::int64_t n : image.grid.size)
      if (n > 32767)
        throw InputError(file.string(), fmt::format("{} voxels along an axis: NIfTI-1 holds at most 32767; write "
                                                    "NRRD (.nrrd) instead",
                                                    n));
    const LargeVector<char> bytes = nifti_bytes(image, values);
    if (ends_with(file.filename().string(), ".gz"))
      write_atomically(file, GzipParts(bytes).parts());
    else
      write_atomically(file, {bytes});
  }
}

}  // namespace mtled
