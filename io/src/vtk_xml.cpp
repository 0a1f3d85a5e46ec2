// XML VTK unstructured-grid reader (.vtu, "VTK File Formats", VTK User's Guide): DataArrays in "ascii",
// inline "binary" (base64) and "appended" (base64 or raw) form, uncompressed or zlib-compressed. Only the few tags a .vtu has
// are understood; the scan stops at <AppendedData>, whose raw bytes may contain anything.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>

#include <zlib.h>

#include "mtled/errors.hpp"
#include "mtled/io/text_cursor.hpp"
#include "mtled/io/vtk_grid.hpp"

namespace mtled::vtk {

namespace {

using mesh_readers::quote_token;
using mesh_readers::TextCursor;

struct XmlTag {
  std::string_view name;
  std::vector<std::pair<std::string_view, std::string_view>> attributes;
  bool closing = false;       // </name>
  bool self_closing = false;  // <name ... />
  std::size_t begin = 0;      // position of '<'
  std::size_t end = 0;        // position after '>'
  long line = 0;

  std::optional<std::string_view> attribute(std::string_view key) const {
    for (const auto& [k, v] : attributes)
      if (k == key) return v;
    return std::nullopt;
  }
};

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

// Finds tags in order; text between them is left to the caller. Line numbers are counted as it goes.
class XmlScanner {
 public:
  XmlScanner(std::string_view text, std::string label) : text_(text), label_(std::move(label)) {}

  std::optional<XmlTag> next() {
    while (true) {
      const std::size_t open = text_.find('<', position_);
      if (open == std::string_view::npos) return std::nullopt;
      position_ = open;
      if (text_.compare(open, 4, "<!--") == 0) {
        skip_past("-->", open);
      } else if (text_.compare(open, 2, "<?") == 0) {
        skip_past("?>", open);
      } else if (text_.compare(open, 2, "<!") == 0) {
        skip_past(">", open);
      } else {
        return read_tag(open);
      }
    }
  }

  long line_at(std::size_t position) {
    // Positions only move forward while scanning; a position behind the counter is counted from the start.
    if (position < counted_position_) {
      counted_position_ = 0;
      counted_line_ = 1;
    }
    for (; counted_position_ < position && counted_position_ < text_.size(); ++counted_position_)
      if (text_[counted_position_] == '\n') ++counted_line_;
    return counted_line_;
  }

  std::string where(std::size_t position) { return fmt::format("{}:{}", label_, line_at(position)); }
  std::string_view text() const { return text_; }
  const std::string& label() const { return label_; }

 private:
  void skip_past(std::string_view end, std::size_t open) {
    const std::size_t close = text_.find(end, open);
    if (close == std::string_view::npos)
      throw InputError(where(open),
                       "the file ends inside an XML comment or declaration: it is truncated; save it again");
    position_ = close + end.size();
  }

  XmlTag read_tag(std::size_t open) {
    XmlTag tag;
    tag.begin = open;
    tag.line = line_at(open);
    std::size_t i = open + 1;
    if (i < text_.size() && text_[i] == '/') {
      tag.closing = true;
      ++i;
    }
    const std::size_t name_begin = i;
    while (i < text_.size() && !is_space(text_[i]) && text_[i] != '>' && text_[i] != '/') ++i;
    tag.name = text_.substr(name_begin, i - name_begin);
    while (true) {
      while (i < text_.size() && is_space(text_[i])) ++i;
      if (i >= text_.size()) fail(tag, "the file ends inside a tag: it is truncated; save it again");
      if (text_[i] == '>') {
        ++i;
        break;
      }
      if (text_[i] == '/' && i + 1 < text_.size() && text_[i + 1] == '>') {
        tag.self_closing = true;
        i += 2;
        break;
      }
      const std::size_t key_begin = i;
      while (i < text_.size() && !is_space(text_[i]) && text_[i] != '=' && text_[i] != '>') ++i;
      const std::string_view key = text_.substr(key_begin, i - key_begin);
      while (i < text_.size() && is_space(text_[i])) ++i;
      if (i >= text_.size() || text_[i] != '=') fail(tag, fmt::format("attribute {} has no value", quote_token(key)));
      ++i;
      while (i < text_.size() && is_space(text_[i])) ++i;
      if (i >= text_.size() || (text_[i] != '"' && text_[i] != '\''))
        fail(tag, fmt::format("the value of attribute {} is not quoted", quote_token(key)));
      const char quote = text_[i++];
      const std::size_t value_end = text_.find(quote, i);
      if (value_end == std::string_view::npos) fail(tag, "the file ends inside a tag: it is truncated; save it again");
      tag.attributes.emplace_back(key, text_.substr(i, value_end - i));
      i = value_end + 1;
    }
    tag.end = i;
    position_ = i;
    return tag;
  }

  [[noreturn]] void fail(const XmlTag& tag, const std::string& message) {
    throw InputError(fmt::format("{}:{}", label_, tag.line), fmt::format("in <{}>: {}", tag.name, message));
  }

  std::string_view text_;
  std::string label_;
  std::size_t position_ = 0;
  std::size_t counted_position_ = 0;
  long counted_line_ = 1;
};

// Base64 (RFC 4648) decoded on demand. '=' padding ends a group, after which decoding goes on: VTK writers
// encode a binary array's header and data either as one stream or as two, and both read the same here.
class Base64Reader {
 public:
  Base64Reader(std::string_view text, std::size_t start) : text_(text), position_(start) {}

  // Appends the next `count` bytes to `out`; false when the base64 text ends first.
  bool read(std::size_t count, std::vector<unsigned char>& out) {
    while (count > 0) {
      if (used_ == available_ && !decode_group()) return false;
      const std::size_t n = std::min<std::size_t>(count, static_cast<std::size_t>(available_ - used_));
      out.insert(out.end(), group_ + used_, group_ + used_ + n);
      used_ += static_cast<int>(n);
      count -= n;
    }
    return true;
  }

 private:
  static int value(char c) {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  }

  bool decode_group() {
    int sextets[4];
    int got = 0, padding = 0;
    while (got < 4) {
      while (position_ < text_.size() && is_space(text_[position_])) ++position_;
      if (position_ >= text_.size()) return false;
      const char c = text_[position_];
      if (c == '=' && got >= 2) {
        sextets[got++] = 0;
        ++padding;
        ++position_;
        continue;
      }
      const int v = value(c);
      if (v < 0 || padding > 0) return false;  // the end of the data ('<', '_', ...) or damaged text
      sextets[got++] = v;
      ++position_;
    }
    const std::uint32_t bits = (static_cast<std::uint32_t>(sextets[0]) << 18) |
                               (static_cast<std::uint32_t>(sextets[1]) << 12) |
                               (static_cast<std::uint32_t>(sextets[2]) << 6) | static_cast<std::uint32_t>(sextets[3]);
    group_[0] = static_cast<unsigned char>(bits >> 16);
    group_[1] = static_cast<unsigned char>(bits >> 8);
    group_[2] = static_cast<unsigned char>(bits);
    available_ = 3 - padding;
    used_ = 0;
    return true;
  }

  std::string_view text_;
  std::size_t position_;
  unsigned char group_[3] = {0, 0, 0};
  int available_ = 0, used_ = 0;
};

// A DataArray's text without the elements VTK nests in it before the values (<InformationKey> with its <Value>s:
// a range or a component name), blanked out so that line numbers stay true.
std::string without_child_elements(std::string_view content) {
  std::string out(content);
  std::size_t at = 0;
  while ((at = out.find('<', at)) != std::string::npos) {
    std::size_t name_end = at + 1;
    while (name_end < out.size() && (std::isalnum(static_cast<unsigned char>(out[name_end])) || out[name_end] == '_'))
      ++name_end;
    const std::string name = out.substr(at + 1, name_end - at - 1);
    const std::size_t tag_end = out.find('>', at);
    std::size_t end = tag_end == std::string::npos ? out.size() : tag_end + 1;
    if (!name.empty() && tag_end != std::string::npos && out[tag_end - 1] != '/') {
      const std::size_t close = out.find("</" + name, tag_end);
      if (close != std::string::npos) end = std::min(out.size(), out.find('>', close) + 1);
    }
    for (std::size_t i = at; i < end; ++i)
      if (out[i] != '\n') out[i] = ' ';
    at = end;
  }
  return out;
}

struct ArraySpec {
  std::string name;
  std::string_view type = "Float32";
  std::string_view format = "ascii";
  int components = 1;
  std::size_t offset = 0;
  std::string_view content;  // ascii and inline binary
  std::size_t content_begin = 0;
  long line = 0;
  bool present = false;
};

struct PieceSpec {
  long long point_count = 0, cell_count = 0;
  long line = 0;
  ArraySpec points, connectivity, offsets, types;
  std::vector<ArraySpec> point_data, cell_data;
};

class VtuParser {
 public:
  VtuParser(const mesh_readers::MeshFileText& file, const ArrayRequest& request)
      : scanner_(file.text, file.label), request_(request) {}

  UnstructuredGrid parse() {
    scan();
    UnstructuredGrid grid;
    for (auto& piece : pieces_) add_piece(grid, piece);
    const std::string space = string_field(space_array_, "SPACE");
    grid.coordinate_system = space == "LPS" || space == "RAS" ? space : "";
    grid.length_unit = string_field(length_unit_array_, "LENGTH_UNIT");
    return grid;
  }

 private:
  enum class Section { none, points, cells, point_data, cell_data, other };

  void scan() {
    std::optional<XmlTag> tag = scanner_.next();
    if (!tag || tag->name != "VTKFile")
      throw InputError(scanner_.where(tag ? tag->begin : 0),
                       "a .vtu file starts with <VTKFile type=\"UnstructuredGrid\" ...>: is this a VTK XML file?");
    read_file_attributes(*tag);
    Section section = Section::none;
    PieceSpec* piece = nullptr;
    while ((tag = scanner_.next())) {
      const std::string_view name = tag->name;
      if (tag->closing) {
        if (name == "Points" || name == "Cells" || name == "PointData" || name == "CellData" || name == "FieldData")
          section = Section::none;
        if (name == "Piece") piece = nullptr;
        if (name == "VTKFile") return;
        continue;
      }
      if (name == "Piece") {
        pieces_.emplace_back();
        piece = &pieces_.back();
        piece->line = tag->line;
        piece->point_count = count_attribute(*tag, "NumberOfPoints");
        piece->cell_count = count_attribute(*tag, "NumberOfCells");
        if (tag->self_closing) piece = nullptr;
      } else if (name == "Points") {
        section = Section::points;
      } else if (name == "Cells") {
        section = Section::cells;
      } else if (name == "PointData") {
        section = Section::point_data;
      } else if (name == "CellData") {
        section = Section::cell_data;
      } else if (name == "FieldData") {
        section = Section::other;
      } else if (name == "Array" && section == Section::other && tag->attribute("Name") == "SPACE") {
        space_array_ = read_array_tag(*tag);  // 3D Slicer's string field data "SPACE": "LPS" or "RAS"
      } else if (name == "Array" && section == Section::other && tag->attribute("Name") == "LENGTH_UNIT") {
        length_unit_array_ = read_array_tag(*tag);  // mtled's results in millimetres: "mm"
      } else if (name == "DataArray") {
        ArraySpec array = read_array_tag(*tag);
        if (piece == nullptr || section == Section::none || section == Section::other) continue;
        place_array(*piece, section, std::move(array));
      } else if (name == "AppendedData") {
        read_appended_start(*tag);
        return;  // raw appended bytes may look like anything: nothing after them is needed
      } else if (name == "UnstructuredGrid" || name == "Verts" || name == "Lines" || name == "Strips" ||
                 name == "Polys" || name == "InformationKey" || name == "Information") {
        // containers without anything mtled needs, or not found in unstructured grids
      }
    }
    if (pieces_.empty())
      throw InputError(scanner_.label(), "the file has no <Piece>: it is truncated or holds no grid; save it again");
  }

  void read_file_attributes(const XmlTag& tag) {
    const auto type = tag.attribute("type");
    if (type != "UnstructuredGrid")
      throw InputError(scanner_.where(tag.begin),
                       fmt::format("this VTK XML file holds a {}: mtled reads tetrahedral meshes stored as "
                                   "UnstructuredGrid (.vtu); convert it (ParaView: Tetrahedralize, then save as .vtu)",
                                   type ? std::string(*type) : std::string("dataset of unknown type")));
    const auto order = tag.attribute("byte_order");
    big_endian_ = order == "BigEndian";
    const auto header = tag.attribute("header_type");
    if (header == "UInt64")
      header_size_ = 8;
    else if (!header || header == "UInt32")
      header_size_ = 4;
    else
      throw InputError(scanner_.where(tag.begin),
                       fmt::format("header_type {} is not UInt32 or UInt64", quote_token(*header)));
    if (const auto compressor = tag.attribute("compressor"); compressor && !compressor->empty()) {
      compressor_ = std::string(*compressor);
      compressor_line_ = tag.line;
    }
  }

  long long count_attribute(const XmlTag& tag, std::string_view key) {
    const auto text = tag.attribute(key);
    const auto value = text ? mesh_readers::parse_integer(*text) : std::nullopt;
    if (!value || *value < 0)
      throw InputError(scanner_.where(tag.begin), fmt::format("<Piece> needs {}=\"n\" with n >= 0{}", key,
                                                              text ? ", found " + quote_token(*text) : ""));
    return *value;
  }

  ArraySpec read_array_tag(const XmlTag& tag) {
    ArraySpec array;
    array.present = true;
    array.line = tag.line;
    array.name = std::string(tag.attribute("Name").value_or(""));
    array.type = tag.attribute("type").value_or("");
    array.format = tag.attribute("format").value_or("ascii");
    if (const auto components = tag.attribute("NumberOfComponents")) {
      const auto c = mesh_readers::parse_integer(*components);
      if (!c || *c < 1 || *c > 1000)
        throw InputError(scanner_.where(tag.begin),
                         fmt::format("NumberOfComponents {} is not a count from 1", quote_token(*components)));
      array.components = static_cast<int>(*c);
    }
    if (tag.name == "DataArray" && !xml_scalar_type(array.type))
      throw InputError(scanner_.where(tag.begin),
                       fmt::format("DataArray {} has type {}: expected Int8 ... Int64, UInt8 ... UInt64, Float32 or "
                                   "Float64",
                                   quote_token(array.name), quote_token(array.type)));
    if (array.format == "appended") {
      const auto offset = tag.attribute("offset");
      const auto value = offset ? mesh_readers::parse_integer(*offset) : std::nullopt;
      if (!value || *value < 0)
        throw InputError(scanner_.where(tag.begin),
                         fmt::format("appended DataArray {} needs offset=\"n\"", quote_token(array.name)));
      array.offset = static_cast<std::size_t>(*value);
      if (!tag.self_closing) skip_to_close(tag);
    } else if (array.format == "ascii" || array.format == "binary") {
      if (tag.self_closing) return array;
      const std::size_t close = scanner_.text().find(fmt::format("</{}", tag.name), tag.end);
      if (close == std::string_view::npos)
        throw InputError(scanner_.where(tag.begin), fmt::format("DataArray {} is never closed: the file is truncated; "
                                                                "save it again",
                                                                quote_token(array.name)));
      array.content = scanner_.text().substr(tag.end, close - tag.end);
      array.content_begin = tag.end;
      skip_to_close(tag);
    } else {
      throw InputError(scanner_.where(tag.begin), fmt::format("DataArray {} has format {}: expected ascii, binary or "
                                                              "appended",
                                                              quote_token(array.name), quote_token(array.format)));
    }
    return array;
  }

  void skip_to_close(const XmlTag& open) {
    while (const auto tag = scanner_.next())
      if (tag->closing && tag->name == open.name) return;
    throw InputError(scanner_.where(open.begin),
                     fmt::format("a {} is never closed: the file is truncated; save it again", open.name));
  }

  void place_array(PieceSpec& piece, Section section, ArraySpec array) {
    switch (section) {
      case Section::points:
        if (!piece.points.present) piece.points = std::move(array);
        break;
      case Section::cells:
        if (array.name == "connectivity")
          piece.connectivity = std::move(array);
        else if (array.name == "offsets")
          piece.offsets = std::move(array);
        else if (array.name == "types")
          piece.types = std::move(array);
        break;
      case Section::point_data:
        piece.point_data.push_back(std::move(array));
        break;
      case Section::cell_data:
        piece.cell_data.push_back(std::move(array));
        break;
      default:
        break;
    }
  }

  void read_appended_start(const XmlTag& tag) {
    const auto encoding = tag.attribute("encoding").value_or("raw");
    if (encoding != "base64" && encoding != "raw")
      throw InputError(scanner_.where(tag.begin),
                       fmt::format("appended data in encoding {}: expected base64 or raw", quote_token(encoding)));
    appended_base64_ = encoding == "base64";
    const std::string_view text = scanner_.text();
    std::size_t i = tag.end;
    while (i < text.size() && is_space(text[i])) ++i;
    if (i >= text.size() || text[i] != '_')
      throw InputError(scanner_.where(tag.begin),
                       "<AppendedData> must be followed by '_' and the data: the file is "
                       "damaged; save it again");
    appended_start_ = i + 1;
  }

  // --- decoding ---

  std::string array_where(const ArraySpec& array) const { return fmt::format("{}:{}", scanner_.label(), array.line); }

  // A string field's text (3D Slicer's "SPACE", mtled's "LENGTH_UNIT"): its characters, ascii (as numbers)
  // or binary; empty when absent.
  std::string string_field(const ArraySpec& array, std::string_view name) {
    if (!array.present || array.type != "String") return "";
    std::string text;
    if (array.format == "ascii") {
      TextCursor cursor(array.content, scanner_.label(), scanner_.line_at(array.content_begin));
      const std::string what = fmt::format("a character code of field \"{}\"", name);
      while (const auto token = cursor.next_token())
        text += static_cast<char>(mesh_readers::to_integer(*token, cursor, what));
    } else {
      for (unsigned char c : binary_bytes(array)) text += static_cast<char>(c);
    }
    return text.substr(0, text.find('\0'));
  }

  // All values of `array` as doubles (integers up to 2^53 are exact).
  std::vector<double> decode(const ArraySpec& array) {
    std::vector<double> values;
    const ScalarType type = *xml_scalar_type(array.type);
    if (array.format == "ascii") {
      const std::string content = without_child_elements(array.content);
      TextCursor cursor(content, scanner_.label(), scanner_.line_at(array.content_begin));
      const std::string what = fmt::format("a value of DataArray \"{}\"", array.name);
      while (const auto token = cursor.next_token()) values.push_back(mesh_readers::to_real(*token, cursor, what));
      return values;
    }
    const std::vector<unsigned char> bytes = binary_bytes(array);
    if (bytes.size() % type.size != 0)
      throw InputError(array_where(array), fmt::format("DataArray \"{}\" holds {} bytes, not a whole number of {}-byte "
                                                       "values: the file is damaged; save it again",
                                                       array.name, bytes.size(), type.size));
    values.resize(bytes.size() / type.size);
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = decode_scalar(&bytes[i * type.size], type, big_endian_);
    for (double v : values)
      if (!std::isfinite(v))
        throw InputError(array_where(array),
                         fmt::format("DataArray \"{}\" holds a value that is not a finite number", array.name));
    return values;
  }

  // The bytes of a binary array (inline base64, or appended base64 or raw), uncompressed.
  std::vector<unsigned char> binary_bytes(const ArraySpec& array) {
    if (!compressor_.empty() && compressor_ != "vtkZLibDataCompressor")
      throw InputError(fmt::format("{}:{}", scanner_.label(), compressor_line_),
                       fmt::format("the file is compressed with {}: mtled reads zlib-compressed and uncompressed "
                                   ".vtu files; save it with zlib (ParaView: Save Data, \"Compressor Type\" ZLib; "
                                   "VTK: writer.SetCompressorTypeToZLib()) or without compression",
                                   compressor_));
    if (array.format == "binary") {
      const std::string content = without_child_elements(array.content);
      Base64Reader reader(content, 0);
      return read_block(array, [&](std::size_t n, std::vector<unsigned char>& out) { return reader.read(n, out); });
    }
    if (appended_start_ == 0)
      throw InputError(array_where(array), fmt::format("DataArray \"{}\" is appended but the file has no "
                                                       "<AppendedData>: it is truncated; save it again",
                                                       array.name));
    const std::string_view text = scanner_.text();
    if (appended_base64_) {
      Base64Reader reader(text, appended_start_ + array.offset);
      return read_block(array, [&](std::size_t n, std::vector<unsigned char>& out) { return reader.read(n, out); });
    }
    std::size_t position = appended_start_ + array.offset;
    return read_block(array, [&](std::size_t n, std::vector<unsigned char>& out) {
      if (position > text.size() || text.size() - position < n) return false;
      out.insert(out.end(), text.begin() + static_cast<std::ptrdiff_t>(position),
                 text.begin() + static_cast<std::ptrdiff_t>(position + n));
      position += n;
      return true;
    });
  }

  // An array's block. Uncompressed: a header with the byte count, then the bytes. Compressed (VTK's
  // vtkZLibDataCompressor): a header [number of blocks, block size, size of the last block (0: full),
  // compressed size of each block], then the blocks, each a zlib stream. Header integers are header_type.
  template <class Read>
  std::vector<unsigned char> read_block(const ArraySpec& array, Read read) {
    std::vector<unsigned char> scratch;
    const auto header_integer = [&] {
      scratch.clear();
      if (!read(header_size_, scratch))
        throw InputError(array_where(array), fmt::format("the binary data of DataArray \"{}\" ends before its "
                                                         "header: the file is truncated or damaged; save it again",
                                                         array.name));
      // As an integer, not through decode_scalar(): as a double, a count near 2^64 rounds up to 2^64, which
      // std::uint64_t cannot hold (undefined behaviour; found by tests/fuzz with UBSan).
      std::uint64_t value = 0;
      for (std::size_t i = 0; i < header_size_; ++i)
        value = (value << 8) | scratch[big_endian_ ? i : header_size_ - 1 - i];
      return value;
    };
    const auto truncated = [&](std::uint64_t size) {
      return InputError(array_where(array), fmt::format("DataArray \"{}\" announces {} bytes but the file holds "
                                                        "fewer: it is truncated or damaged; save it again",
                                                        array.name, size));
    };
    constexpr std::uint64_t kLargest = std::uint64_t{1} << 36;  // no mesh file is larger: a damaged count
    std::vector<unsigned char> bytes;
    if (compressor_.empty()) {
      const std::uint64_t size = header_integer();
      if (size > kLargest || !read(static_cast<std::size_t>(size), bytes)) throw truncated(size);
      return bytes;
    }
    const std::uint64_t blocks = header_integer(), block_size = header_integer(), last_size = header_integer();
    if (block_size > kLargest || last_size > block_size || (blocks > 0 && block_size == 0) ||
        blocks > kLargest / std::max<std::uint64_t>(block_size, 1))
      throw InputError(array_where(array), fmt::format("the compression header of DataArray \"{}\" is damaged ({} "
                                                       "blocks of {} bytes); save the file again",
                                                       array.name, blocks, block_size));
    std::vector<std::uint64_t> compressed_sizes;  // grown, not sized: a damaged count fails at the file's end
    for (std::uint64_t b = 0; b < blocks; ++b) compressed_sizes.push_back(header_integer());
    for (std::uint64_t b = 0; b < blocks; ++b) {
      const std::uint64_t expected = (b + 1 == blocks && last_size != 0) ? last_size : block_size;
      const std::uint64_t size = compressed_sizes[static_cast<std::size_t>(b)];
      scratch.clear();
      if (size > kLargest || !read(static_cast<std::size_t>(size), scratch)) throw truncated(size);
      const std::size_t at = bytes.size();
      bytes.resize(at + static_cast<std::size_t>(expected));
      uLongf produced = static_cast<uLongf>(expected);
      if (uncompress(bytes.data() + at, &produced, scratch.data(), static_cast<uLong>(size)) != Z_OK ||
          produced != expected)
        throw InputError(array_where(array), fmt::format("block {} of {} of DataArray \"{}\" does not decompress to "
                                                         "its {} bytes: the file is damaged; save it again",
                                                         b + 1, blocks, array.name, expected));
    }
    return bytes;
  }

  std::vector<long long> decode_integers(const ArraySpec& array, std::size_t expected, std::string_view role) {
    if (!array.present)
      throw InputError(piece_where_, fmt::format("the <Piece> has no \"{}\" DataArray in <Cells>: the file is damaged; "
                                                 "save it again",
                                                 role));
    const std::vector<double> values = decode(array);
    if (expected != std::string_view::npos && values.size() != expected)
      throw InputError(array_where(array), fmt::format("DataArray \"{}\" holds {} values, expected {} (one per cell): "
                                                       "the file is damaged; save it again",
                                                       array.name, values.size(), expected));
    std::vector<long long> integers(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (values[i] != std::floor(values[i]) || std::abs(values[i]) > 9.0e15)
        throw InputError(array_where(array),
                         fmt::format("DataArray \"{}\" holds {}, not an integer", array.name, values[i]));
      integers[i] = static_cast<long long>(values[i]);
    }
    return integers;
  }

  void add_piece(UnstructuredGrid& grid, const PieceSpec& piece) {
    piece_where_ = fmt::format("{}:{}", scanner_.label(), piece.line);
    const std::size_t first_point = grid.points.size();
    const auto n_points = static_cast<std::size_t>(piece.point_count);
    const auto n_cells = static_cast<std::size_t>(piece.cell_count);
    if (n_points > 0) {
      if (!piece.points.present)
        throw InputError(piece_where_,
                         "the <Piece> has points but no <Points> DataArray: the file is damaged; save it "
                         "again");
      if (piece.points.components != 3)
        throw InputError(array_where(piece.points),
                         fmt::format("the points have {} components, expected 3", piece.points.components));
      const std::vector<double> xyz = decode(piece.points);
      // Divided, not multiplied: 3 * NumberOfPoints wraps around for a damaged count near 2^64 / 3 and could
      // then match a short array, whose end the loop below would read past.
      if (xyz.size() % 3 != 0 || xyz.size() / 3 != n_points)
        throw InputError(array_where(piece.points), fmt::format("the points DataArray holds {} values, expected {} "
                                                                "(3 for each of {} points): the file is truncated or "
                                                                "damaged; save it again",
                                                                xyz.size(), 3.0 * static_cast<double>(n_points),
                                                                n_points));
      for (std::size_t i = 0; i < n_points; ++i) grid.points.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    }
    if (n_cells > 0) {
      const auto types = decode_integers(piece.types, n_cells, "types");
      const auto ends = decode_integers(piece.offsets, n_cells, "offsets");
      const auto connectivity = decode_integers(piece.connectivity, std::string_view::npos, "connectivity");
      const std::string where = array_where(piece.connectivity);
      add_cells(grid, ends, connectivity, types, first_point, n_points, [&](std::size_t) { return where; });
    }
    add_data(grid.cell_arrays, piece.cell_data, n_cells, true);
    add_data(grid.point_arrays, piece.point_data, n_points, false);
  }

  // Data arrays of a piece, appended to those of earlier pieces (same name) or new.
  void add_data(std::vector<DataArray>& arrays, const std::vector<ArraySpec>& specs, std::size_t tuples, bool cells) {
    for (const auto& spec : specs) {
      DataArray* target = nullptr;
      for (auto& a : arrays)
        if (a.name == spec.name) target = &a;
      if (target == nullptr) {
        arrays.push_back(DataArray{spec.name, spec.components, {}, array_where(spec)});
        target = &arrays.back();
      }
      if (!(cells ? request_.wants_cell(spec.name) : request_.wants_point(spec.name))) continue;
      const std::vector<double> values = decode(spec);
      if (values.size() % static_cast<std::size_t>(spec.components) != 0 ||
          values.size() / static_cast<std::size_t>(spec.components) != tuples)  // divided: see add_piece
        throw InputError(array_where(spec),
                         fmt::format("DataArray \"{}\" holds {} values, expected {} ({} {} x {} "
                                     "components): the file is truncated or damaged; save it again",
                                     spec.name, values.size(), tuples * static_cast<std::size_t>(spec.components),
                                     tuples, cells ? "cells" : "points", spec.components));
      target->values.insert(target->values.end(), values.begin(), values.end());
    }
  }

  XmlScanner scanner_;
  const ArrayRequest& request_;
  std::vector<PieceSpec> pieces_;
  bool big_endian_ = false;
  std::size_t header_size_ = 4;
  std::string compressor_;
  ArraySpec space_array_, length_unit_array_;
  long compressor_line_ = 0;
  bool appended_base64_ = false;
  std::size_t appended_start_ = 0;
  std::string piece_where_;
};

}  // namespace

double metres_per_length_unit(const UnstructuredGrid& grid, const std::string& label) {
  if (grid.length_unit.empty()) return 1.0;
  if (grid.length_unit == "mm") return 1e-3;
  throw InputError(label, fmt::format("field LENGTH_UNIT says \"{}\"; mtled writes \"mm\" or no such field (metres)",
                                      grid.length_unit));
}

UnstructuredGrid read_vtu(const mesh_readers::MeshFileText& file, const ArrayRequest& request) {
  return VtuParser(file, request).parse();
}

}  // namespace mtled::vtk
