#include "mtled/io/image_write.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <bit>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "mtled/errors.hpp"

namespace fs = std::filesystem;

namespace mtled {

std::string gzip(const std::string& bytes) {
  z_stream stream{};
  if (deflateInit2(&stream, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
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

void write_nrrd_vectors(const fs::path& file, const VoxelGrid& grid, const std::string& space,
                        std::span<const Vec3> vectors) {
  static_assert(std::endian::native == std::endian::little, "the NRRD header says little endian");
  const auto vector = [](const Vec3& v) { return fmt::format("({:.17g},{:.17g},{:.17g})", v[0], v[1], v[2]); };
  const Mat3 axes_mm = 1e3 * grid.axes;
  std::string header = fmt::format(
      "NRRD0004\n# Complete NRRD file format specification at:\n# http://teem.sourceforge.net/nrrd/format.html\n"
      "type: float\ndimension: 4\nspace: {}\nsizes: 3 {} {} {}\nspace directions: none {} {} {}\n"
      "kinds: vector domain domain domain\nendian: little\nencoding: gzip\nspace origin: {}\nspace units: \"mm\" "
      "\"mm\" \"mm\"\n\n",
      space == "RAS" ? "right-anterior-superior" : "left-posterior-superior", grid.size[0], grid.size[1], grid.size[2],
      vector(axes_mm.col(0)), vector(axes_mm.col(1)), vector(axes_mm.col(2)), vector(1e3 * grid.origin));
  std::vector<float> values;
  values.reserve(3 * vectors.size());
  for (const Vec3& v : vectors)
    for (int c = 0; c < 3; ++c) values.push_back(static_cast<float>(1e3 * v[c]));  // millimetres
  std::string raw(values.size() * sizeof(float), '\0');
  std::memcpy(raw.data(), values.data(), raw.size());
  const fs::path temporary = file.parent_path() / ("." + file.filename().string() + ".tmp");
  {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw InputError(file.string(), "cannot write the image here: check the folder exists and is writable");
    out << header << gzip(raw);
    if (!out.flush()) throw std::runtime_error(fmt::format("writing {} failed (disk full?)", file.string()));
  }
  fs::rename(temporary, file);
}

}  // namespace mtled
