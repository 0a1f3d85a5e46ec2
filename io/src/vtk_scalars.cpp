// Binary values of VTK data arrays: the type names of both file formats and the decoding of one value.
#include <cstdint>
#include <cstring>
#include <utility>

#include "mtled/io/text_cursor.hpp"
#include "mtled/io/vtk_grid.hpp"

namespace mtled::vtk {

std::optional<ScalarType> xml_scalar_type(std::string_view name) {
  if (name == "Int8") return ScalarType{ScalarKind::signed_integer, 1};
  if (name == "UInt8") return ScalarType{ScalarKind::unsigned_integer, 1};
  if (name == "Int16") return ScalarType{ScalarKind::signed_integer, 2};
  if (name == "UInt16") return ScalarType{ScalarKind::unsigned_integer, 2};
  if (name == "Int32") return ScalarType{ScalarKind::signed_integer, 4};
  if (name == "UInt32") return ScalarType{ScalarKind::unsigned_integer, 4};
  if (name == "Int64") return ScalarType{ScalarKind::signed_integer, 8};
  if (name == "UInt64") return ScalarType{ScalarKind::unsigned_integer, 8};
  if (name == "Float32") return ScalarType{ScalarKind::real, 4};
  if (name == "Float64") return ScalarType{ScalarKind::real, 8};
  return std::nullopt;
}

// Legacy names as VTK's writers spell them (vtkDataWriter); "long" is 8 bytes as VTK writes it on the
// 64-bit Linux and macOS systems that produce such files.
std::optional<ScalarType> legacy_scalar_type(std::string_view name) {
  const std::string lower = mesh_readers::lowercase(name);
  // Fixed-size names ("vtktypeint32", "vtktypeuint8", "vtktypefloat64": VTK 9 and meshio write them).
  for (const auto& [prefix, kind] : {std::pair{"vtktypeuint", ScalarKind::unsigned_integer},
                                     std::pair{"vtktypeint", ScalarKind::signed_integer},
                                     std::pair{"vtktypefloat", ScalarKind::real}}) {
    const std::string_view p = prefix;
    if (lower.rfind(p, 0) != 0) continue;
    const std::string bits = lower.substr(p.size());
    const bool real = kind == ScalarKind::real;
    if (bits == "8" && !real) return ScalarType{kind, 1};
    if (bits == "16" && !real) return ScalarType{kind, 2};
    if (bits == "32") return ScalarType{kind, 4};
    if (bits == "64") return ScalarType{kind, 8};
    return std::nullopt;
  }
  if (lower == "char" || lower == "signed_char") return ScalarType{ScalarKind::signed_integer, 1};
  if (lower == "unsigned_char") return ScalarType{ScalarKind::unsigned_integer, 1};
  if (lower == "short") return ScalarType{ScalarKind::signed_integer, 2};
  if (lower == "unsigned_short") return ScalarType{ScalarKind::unsigned_integer, 2};
  if (lower == "int") return ScalarType{ScalarKind::signed_integer, 4};
  if (lower == "unsigned_int") return ScalarType{ScalarKind::unsigned_integer, 4};
  if (lower == "long" || lower == "vtkidtype")
    return ScalarType{ScalarKind::signed_integer, 8};
  if (lower == "unsigned_long") return ScalarType{ScalarKind::unsigned_integer, 8};
  if (lower == "float") return ScalarType{ScalarKind::real, 4};
  if (lower == "double") return ScalarType{ScalarKind::real, 8};
  return std::nullopt;
}

namespace {
template <class T>
double read_as(const unsigned char* bytes) {
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return static_cast<double>(value);
}

// An integer of `size` bytes, signed or unsigned as the type T of that size.
template <class Signed, class Unsigned>
double read_integer(const unsigned char* bytes, bool is_signed) {
  return is_signed ? read_as<Signed>(bytes) : read_as<Unsigned>(bytes);
}
}  // namespace

double decode_scalar(const unsigned char* data, ScalarType type, bool big_endian) {
  unsigned char b[8];
  std::memcpy(b, data, type.size);
  if (big_endian)
    for (std::size_t i = 0; i < type.size / 2; ++i) std::swap(b[i], b[type.size - 1 - i]);
  if (type.kind == ScalarKind::real) return type.size == 4 ? read_as<float>(b) : read_as<double>(b);
  const bool is_signed = type.kind == ScalarKind::signed_integer;
  switch (type.size) {
    case 1: return read_integer<std::int8_t, std::uint8_t>(b, is_signed);
    case 2: return read_integer<std::int16_t, std::uint16_t>(b, is_signed);
    case 4: return read_integer<std::int32_t, std::uint32_t>(b, is_signed);
    default: return read_integer<std::int64_t, std::uint64_t>(b, is_signed);
  }
}

}  // namespace mtled::vtk
