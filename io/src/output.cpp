#include "mtled/io/output.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <string_view>

#include "mtled/errors.hpp"

namespace fs = std::filesystem;

namespace mtled {

namespace {
const char* const kOutputs[] = {"summary.json",
                                "result.vtu",
                                "series.pvd",
                                "needle.csv",
                                "needle_transient.csv",
                                "reactions.csv",
                                "reactions_transient.csv",
                                "histograms.svg",
                                "compare.json",
                                "displacement_field.nrrd",
                                "displacement_field.nii.gz",
                                "last_good_state.vtu"};

fs::path temporary_name(const fs::path& final_path) {
  return final_path.parent_path() / fmt::format(".{}.{}.tmp", final_path.filename().string(), ::getpid());
}
}  // namespace

OutputFolder::OutputFolder(fs::path folder) : folder_(std::move(folder)) {
  std::error_code ec;
  fs::create_directories(folder_, ec);
  if (ec || !fs::is_directory(folder_))
    throw InputError(folder_.string(), fmt::format("cannot create the output folder: {}; choose another with -o",
                                                   ec ? ec.message() : "a file of that name exists"));
  const fs::path probe = folder_ / fmt::format(".mtled-write-test.{}", ::getpid());
  {
    std::ofstream test(probe);
    if (!test)
      throw InputError(folder_.string(), "the output folder is not writable; choose another with -o or fix its "
                                         "permissions");
  }
  fs::remove(probe, ec);
}

void OutputFolder::clear_previous_outputs() const {
  std::error_code ec;
  for (const char* name : kOutputs) fs::remove(folder_ / name, ec);
  fs::remove_all(folder_ / "steps", ec);
  for (const auto& entry : fs::directory_iterator(folder_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > 8 && name.compare(name.size() - 8, 8, ".partial") == 0) fs::remove(entry.path(), ec);
  }
}

void OutputFolder::write_file(const std::string& name, const std::function<void(std::ostream&)>& write) const {
  const fs::path final_path = folder_ / name;
  fs::create_directories(final_path.parent_path());
  const fs::path temporary = temporary_name(final_path);
  {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw std::runtime_error(fmt::format("cannot write {}", temporary.string()));
    write(out);
    out.flush();
    if (!out) throw std::runtime_error(fmt::format("writing {} failed (disk full?)", final_path.string()));
  }
  fs::rename(temporary, final_path);
}

OutputFolder::Stream::Stream(fs::path final_path)
    : final_path_(std::move(final_path)), partial_path_(final_path_.string() + ".partial"), out_(partial_path_) {
  if (!out_) throw std::runtime_error(fmt::format("cannot write {}", partial_path_.string()));
}

void OutputFolder::Stream::commit() {
  if (!out_.is_open()) return;
  out_.close();
  fs::rename(partial_path_, final_path_);
}

OutputFolder::Stream OutputFolder::open_stream(const std::string& name) const { return Stream(folder_ / name); }

namespace {

// One DataArray of a result file: its values row by row, the VTK type they are stored as, and the digits
// they need as text (17: doubles exactly).
struct VtuArray {
  std::string name;  // empty for the points, which VTK leaves unnamed
  std::string type;  // "Float64", "Int64", "Int32" or "UInt8"
  int components = 1;
  int digits = 17;
  std::vector<double> values;
};

template <class T>
std::vector<unsigned char> bytes_as(const std::vector<double>& values) {
  std::vector<unsigned char> bytes(values.size() * sizeof(T));
  for (std::size_t i = 0; i < values.size(); ++i) {
    const T value = static_cast<T>(values[i]);
    std::memcpy(bytes.data() + i * sizeof(T), &value, sizeof(T));
  }
  return bytes;
}

std::vector<unsigned char> raw_bytes(const VtuArray& array) {
  if (array.type == "Float64") return bytes_as<double>(array.values);
  if (array.type == "Int64") return bytes_as<std::int64_t>(array.values);
  if (array.type == "Int32") return bytes_as<std::int32_t>(array.values);
  return bytes_as<std::uint8_t>(array.values);
}

std::string base64(std::string_view bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t group = 0;
    for (std::size_t k = 0; k < 3; ++k)
      group = (group << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k) out += k <= n ? kDigits[(group >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

// VTK's zlib layout: a UInt64 header [number of blocks, block size, size of the last block (0 when full),
// compressed size of each block], then the blocks, each a zlib stream of up to 32 KiB of the data. Header
// and blocks base64-encoded each on its own, as VTK's writer does: raw bytes are smaller by a quarter, but
// an XML parser may take them for text (meshio 5 then fails to read the file).
std::string zlib_blocks(const std::vector<unsigned char>& data) {
  constexpr std::size_t kBlock = 32768;
  const std::size_t blocks = (data.size() + kBlock - 1) / kBlock;
  std::vector<std::uint64_t> header = {blocks, kBlock, data.size() % kBlock};
  std::string compressed;
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t size = std::min(kBlock, data.size() - b * kBlock);
    std::string block(compressBound(static_cast<uLong>(size)), '\0');
    uLongf length = static_cast<uLongf>(block.size());
    if (compress2(reinterpret_cast<Bytef*>(block.data()), &length, data.data() + b * kBlock, static_cast<uLong>(size),
                  Z_DEFAULT_COMPRESSION) != Z_OK)
      throw std::runtime_error("zlib could not compress a result array");
    header.push_back(length);
    compressed.append(block.data(), length);
  }
  return base64({reinterpret_cast<const char*>(header.data()), header.size() * sizeof(std::uint64_t)}) +
         base64(compressed);
}

std::string data_array_tag(const VtuArray& array, const std::string& format_attributes) {
  return fmt::format("<DataArray type=\"{}\"{} NumberOfComponents=\"{}\" {}>", array.type,
                     array.name.empty() ? "" : fmt::format(" Name=\"{}\"", array.name), array.components,
                     format_attributes);
}

std::vector<VtuArray> result_arrays(const TetMesh& mesh, std::span<const double> displacement,
                                    const std::vector<CellField>& cell_fields, double length_scale) {
  const std::size_t n = mesh.points.size(), cells = mesh.tets.size();
  std::vector<VtuArray> arrays;
  arrays.push_back({"displacement", "Float64", 3, 17, {displacement.begin(), displacement.end()}});
  for (double& value : arrays.back().values) value *= length_scale;
  std::vector<double> point_region(n, std::numeric_limits<int>::max());
  for (std::size_t t = 0; t < cells; ++t)
    for (Index v : mesh.tets[t]) point_region[v] = std::min<double>(point_region[v], mesh.tet_region[t]);
  arrays.push_back({"region", "Int32", 1, 10, std::move(point_region)});
  arrays.push_back({"region", "Int32", 1, 10, {mesh.tet_region.begin(), mesh.tet_region.end()}});
  for (const auto& field : cell_fields) arrays.push_back({field.name, "Float64", field.components, 10, field.values});
  VtuArray points{"", "Float64", 3, 17, {}};
  for (const auto& p : mesh.points)
    for (const double x : p) points.values.push_back(x * length_scale);
  arrays.push_back(std::move(points));
  VtuArray connectivity{"connectivity", "Int64", 1, 10, {}}, offsets{"offsets", "Int64", 1, 10, {}};
  for (std::size_t t = 0; t < cells; ++t) {
    connectivity.values.insert(connectivity.values.end(), mesh.tets[t].begin(), mesh.tets[t].end());
    offsets.values.push_back(static_cast<double>(4 * (t + 1)));
  }
  arrays.push_back(std::move(connectivity));
  arrays.push_back(std::move(offsets));
  arrays.push_back({"types", "UInt8", 1, 3, std::vector<double>(cells, 10.0)});  // VTK_TETRA
  return arrays;
}

}  // namespace

void write_vtu(std::ostream& out, const TetMesh& mesh, std::span<const double> displacement,
               const std::vector<CellField>& cell_fields, const VtuStyle& style) {
  const bool millimetres = style.length_unit == LengthUnit::millimetre;
  const std::vector<VtuArray> arrays = result_arrays(mesh, displacement, cell_fields, millimetres ? 1e3 : 1.0);
  const bool binary = style.format == VtuFormat::binary;
  std::vector<std::string> appended;  // binary: each array's compressed block, in file order
  std::size_t offset = 0;
  const auto write_array = [&](const VtuArray& array) {
    if (binary) {
      appended.push_back(zlib_blocks(raw_bytes(array)));
      out << data_array_tag(array, fmt::format("format=\"appended\" offset=\"{}\"", offset)) << "</DataArray>\n";
      offset += appended.back().size();
      return;
    }
    out << data_array_tag(array, "format=\"ascii\"") << '\n';
    for (std::size_t i = 0; i < array.values.size(); ++i)
      out << fmt::format("{:.{}g}{}", array.values[i], array.digits,
                         (i + 1) % static_cast<std::size_t>(array.components) == 0 ? '\n' : ' ');
    out << "</DataArray>\n";
  };
  out << "<?xml version=\"1.0\"?>\n"
      << fmt::format("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"{}\" header_type=\"UInt64\"{}>\n",
                     std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian",
                     binary ? " compressor=\"vtkZLibDataCompressor\"" : "")
      << "<UnstructuredGrid>\n";
  // A mesh from 3D Slicer tagged RAS keeps its tag (Slicer reads an untagged file as LPS, its default; meshio reads
  // no file with a string field, so LPS stays untagged: summary.json records it), as Slicer writes it: a string
  // array of the characters and a 0. The length unit is tagged the same way.
  const auto string_field = [&](std::string_view name, std::string_view text) {
    out << fmt::format("<Array type=\"String\" Name=\"{}\" NumberOfTuples=\"1\" format=\"ascii\">", name);
    for (const char c : text) out << static_cast<int>(c) << ' ';
    out << "0</Array>\n";
  };
  if (mesh.coordinate_system == "RAS" || millimetres) {
    out << "<FieldData>\n";
    if (mesh.coordinate_system == "RAS") string_field("SPACE", "RAS");
    if (millimetres) string_field("LENGTH_UNIT", "mm");
    out << "</FieldData>\n";
  }
  out << fmt::format("<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", mesh.points.size(), mesh.tets.size())
      << "<PointData Vectors=\"displacement\">\n";
  const std::size_t first_cell_array = 2, points = arrays.size() - 4;
  for (std::size_t a = 0; a < arrays.size(); ++a) {
    if (a == first_cell_array) out << "</PointData>\n<CellData>\n";
    if (a == points) out << "</CellData>\n<Points>\n";
    if (a == points + 1) out << "</Points>\n<Cells>\n";
    write_array(arrays[a]);
  }
  out << "</Cells>\n</Piece>\n</UnstructuredGrid>\n";
  if (binary) {
    out << "<AppendedData encoding=\"base64\">\n_";
    for (const auto& block : appended) out.write(block.data(), static_cast<std::streamsize>(block.size()));
    out << "\n</AppendedData>\n";
  }
  out << "</VTKFile>\n";
}

}  // namespace mtled
