// NRRD (Teem's "nearly raw raster data", the format 3D Slicer saves volumes, segmentations and grid transforms in): a
// text header of "field: value" lines and "key:=value" pairs up to a blank line, then the voxels. Read: one 3-D
// volume of scalars, or of 3-vectors ("kinds: vector domain domain domain", a displacement field), with an attached
// header, raw or gzip encoded, placed by "space", "space directions" and "space origin" (else "spacings").
#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <sstream>

#include "image_voxels.hpp"
#include "mtled/errors.hpp"
#include "mtled/io/image.hpp"

namespace mtled {

namespace {

using Kind = VoxelKind;

struct NrrdHeader {
  std::map<std::string, std::string> fields;     // lower-case field name -> value
  std::map<std::string, std::string> key_values;  // "key:=value" pairs
  std::size_t data_offset = 0;
};

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

NrrdHeader read_header(const std::string& bytes, const std::string& source) {
  if (bytes.rfind("NRRD000", 0) != 0)
    throw InputError(source, "not a NRRD file: it must start with \"NRRD000\" (a magic line such as NRRD0004)");
  NrrdHeader header;
  std::size_t pos = bytes.find('\n');
  for (int line = 2; pos != std::string::npos; ++line) {
    const std::size_t end = bytes.find('\n', pos + 1);
    if (end == std::string::npos) break;
    const std::string text = trim(bytes.substr(pos + 1, end - pos - 1));
    pos = end;
    if (text.empty()) {
      header.data_offset = end + 1;
      return header;
    }
    if (text[0] == '#') continue;
    if (const auto kv = text.find(":="); kv != std::string::npos) {
      header.key_values[text.substr(0, kv)] = text.substr(kv + 2);
    } else if (const auto colon = text.find(": "); colon != std::string::npos) {
      std::string field = text.substr(0, colon);
      for (char& c : field) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      header.fields[field] = trim(text.substr(colon + 2));
    } else {
      throw InputError(fmt::format("{}:{}", source, line), fmt::format("\"{}\" is neither \"field: value\" nor "
                                                                       "\"key:=value\"", text));
    }
  }
  throw InputError(source, "the NRRD header never ends (no blank line before the data): the file is truncated");
}

const std::string& field(const NrrdHeader& header, const std::string& name, const std::string& source) {
  const auto it = header.fields.find(name);
  if (it == header.fields.end())
    throw InputError(source, fmt::format("the NRRD header has no \"{}\" field, which an image needs", name));
  return it->second;
}

VoxelType stored_type(const std::string& name, const std::string& source) {
  static const std::map<std::string, VoxelType> types = {
      {"uchar", {Kind::unsigned_integer, 1}},   {"unsigned char", {Kind::unsigned_integer, 1}},
      {"uint8", {Kind::unsigned_integer, 1}},   {"uint8_t", {Kind::unsigned_integer, 1}},
      {"signed char", {Kind::signed_integer, 1}}, {"int8", {Kind::signed_integer, 1}},
      {"int8_t", {Kind::signed_integer, 1}},    {"short", {Kind::signed_integer, 2}},
      {"short int", {Kind::signed_integer, 2}}, {"int16", {Kind::signed_integer, 2}},
      {"int16_t", {Kind::signed_integer, 2}},   {"ushort", {Kind::unsigned_integer, 2}},
      {"unsigned short", {Kind::unsigned_integer, 2}}, {"uint16", {Kind::unsigned_integer, 2}},
      {"uint16_t", {Kind::unsigned_integer, 2}}, {"int", {Kind::signed_integer, 4}},
      {"int32", {Kind::signed_integer, 4}},     {"int32_t", {Kind::signed_integer, 4}},
      {"uint", {Kind::unsigned_integer, 4}},    {"unsigned int", {Kind::unsigned_integer, 4}},
      {"uint32", {Kind::unsigned_integer, 4}},  {"uint32_t", {Kind::unsigned_integer, 4}},
      {"longlong", {Kind::signed_integer, 8}},  {"int64", {Kind::signed_integer, 8}},
      {"int64_t", {Kind::signed_integer, 8}},   {"ulonglong", {Kind::unsigned_integer, 8}},
      {"uint64", {Kind::unsigned_integer, 8}},  {"uint64_t", {Kind::unsigned_integer, 8}},
      {"float", {Kind::floating, 4}},           {"double", {Kind::floating, 8}}};
  const auto it = types.find(name);
  if (it == types.end())
    throw InputError(source, fmt::format("type: \"{}\" is not a NRRD scalar type (uchar, short, int, float, ...)", name));
  return it->second;
}

// "(a,b,c) (d,e,f) (g,h,i)": one vector per axis.
std::vector<Vec3> vectors(const std::string& text, const std::string& source, const std::string& name) {
  std::vector<Vec3> out;
  std::size_t pos = 0;
  while ((pos = text.find('(', pos)) != std::string::npos) {
    const std::size_t end = text.find(')', pos);
    if (end == std::string::npos) break;
    std::string inner = text.substr(pos + 1, end - pos - 1);
    for (char& c : inner) c = c == ',' ? ' ' : c;
    std::istringstream in(inner);
    Vec3 v;
    if (!(in >> v[0] >> v[1] >> v[2]))
      throw InputError(source, fmt::format("{}: \"({})\" is not a vector of three numbers", name, inner));
    out.push_back(v);
    pos = end + 1;
  }
  return out;
}

// Metres per unit of the header's lengths ("space units", millimetres when absent).
double length_unit(const NrrdHeader& header, const std::string& source) {
  const auto it = header.fields.find("space units");
  if (it == header.fields.end()) return 1e-3;
  const std::string& units = it->second;
  if (units.find("\"mm\"") != std::string::npos) return 1e-3;
  if (units.find("\"um\"") != std::string::npos) return 1e-6;
  if (units.find("\"m\"") != std::string::npos) return 1.0;
  throw InputError(source, fmt::format("space units: \"{}\" is not a length unit this reader knows (\"mm\", \"um\", "
                                       "\"m\")", units));
}

std::string space_tag(const NrrdHeader& header, const std::string& source) {
  const auto it = header.fields.find("space");
  if (it == header.fields.end()) return "";
  const std::string& space = it->second;
  if (space == "right-anterior-superior" || space == "RAS") return "RAS";
  if (space == "left-posterior-superior" || space == "LPS") return "LPS";
  throw InputError(source, fmt::format("space: \"{}\" is not a patient frame this reader knows "
                                       "(right-anterior-superior or left-posterior-superior)", space));
}

void place(Image& image, const NrrdHeader& header, const std::string& source, double unit) {
  VoxelGrid& grid = image.grid;
  if (const auto it = header.fields.find("space directions"); it != header.fields.end()) {
    const auto axes = vectors(it->second, source, "space directions");
    if (axes.size() != 3)
      throw InputError(source, fmt::format("space directions: {} vectors for a 3-D image (one per domain axis, each "
                                           "\"(x,y,z)\"; \"none\" for a vector axis)", axes.size()));
    for (int a = 0; a < 3; ++a) grid.axes.col(a) = unit * axes[static_cast<std::size_t>(a)];
    if (const auto origin = header.fields.find("space origin"); origin != header.fields.end()) {
      const auto o = vectors(origin->second, source, "space origin");
      if (o.size() != 1) throw InputError(source, "space origin: expected one vector \"(x,y,z)\"");
      grid.origin = unit * o[0];
    }
  } else if (const auto spacings = header.fields.find("spacings"); spacings != header.fields.end()) {
    std::istringstream in(spacings->second);
    std::vector<double> numbers;
    for (std::string word; in >> word;)
      if (word != "nan" && word != "NaN") numbers.push_back(std::atof(word.c_str()));  // a vector axis has "nan"
    if (numbers.size() != 3) throw InputError(source, "spacings: expected three numbers (one per domain axis)");
    grid.axes = (unit * Vec3(numbers[0], numbers[1], numbers[2])).asDiagonal();
  }
  image.space = space_tag(header, source);
  image_voxels::check_grid(grid, source, "space directions");
}

// The number of values per voxel: 1 for a 3-D image, 3 for a 4-D one whose first axis is a vector.
int components(const NrrdHeader& header, const std::string& dimension, std::istringstream& sizes,
               const std::string& source) {
  if (dimension == "3") return 1;
  const auto kinds = header.fields.find("kinds");
  std::string first_kind;
  if (kinds != header.fields.end()) std::istringstream(kinds->second) >> first_kind;
  std::int64_t length = 0;
  if (dimension != "4" || !(sizes >> length) || length != 3 ||
      (first_kind != "vector" && first_kind != "3-vector" && first_kind != "covariant-vector"))
    throw InputError(source, fmt::format("dimension: {}; an image here is one 3-D volume of scalars, or of 3-vectors "
                                         "(dimension 4, sizes 3 ..., kinds vector domain domain domain). A "
                                         "segmentation with overlapping segments has a 4th axis of layers: in "
                                         "Slicer export it as a labelmap volume", dimension));
  return 3;
}

}  // namespace

Image parse_nrrd(const std::string& bytes, const std::string& source) {
  const NrrdHeader header = read_header(bytes, source);
  if (header.fields.count("data file") != 0)
    throw InputError(source, "data file: the voxels are in a detached file; save the image with an attached header "
                             "(one .nrrd or .seg.nrrd file, Slicer's default)");
  for (const char* skip : {"byte skip", "line skip"})
    if (header.fields.count(skip) != 0 && header.fields.at(skip) != "0")
      throw InputError(source, fmt::format("{}: skipped data before the voxels is not supported", skip));
  Image image;
  image.source = source;
  image.key_values = header.key_values;
  std::istringstream sizes(field(header, "sizes", source));
  image.components = components(header, field(header, "dimension", source), sizes, source);
  if (!(sizes >> image.grid.size[0] >> image.grid.size[1] >> image.grid.size[2]))
    throw InputError(source, "sizes: expected three whole numbers (one per domain axis)");
  const double unit = length_unit(header, source);
  place(image, header, source, unit);
  image.type = stored_type(field(header, "type", source), source);
  const std::string encoding = field(header, "encoding", source);
  std::string gunzipped;
  const char* data = bytes.data() + header.data_offset;
  std::size_t available = bytes.size() - header.data_offset;
  if (encoding == "gzip" || encoding == "gz") {
    gunzipped = gunzip(bytes.substr(header.data_offset), source);
    data = gunzipped.data();
    available = gunzipped.size();
  } else if (encoding != "raw") {
    throw InputError(source, fmt::format("encoding: \"{}\" is not supported (raw or gzip; Slicer writes gzip)", encoding));
  }
  const std::int64_t count = image.grid.count() * image.components;
  const auto needed = static_cast<std::size_t>(count * image.type.bytes);
  if (available < needed)
    throw InputError(source, fmt::format("the voxel data is truncated: {} bytes for {} values of {} bytes ({} needed)",
                                         available, count, image.type.bytes, needed));
  const auto endian = header.fields.find("endian");
  const bool big = endian != header.fields.end() && endian->second == "big";
  const bool swap = image.type.bytes > 1 && big != (std::endian::native == std::endian::big);
  image.values = image_voxels::decode(data, count, image.type, swap);
  if (image.components == 3)
    for (double& v : image.values) v *= unit;  // displacements are lengths in the space's unit
  return image;
}

}  // namespace mtled
