#include "mtled/markups.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <iterator>

#include "mtled/errors.hpp"
#include "mtled/json.hpp"

namespace mtled {

namespace {

Vec3 markup_position(const json& point, const std::string& where) {
  const auto position = point.find("position");
  if (position == point.end() || !position->is_array() || position->size() != 3 ||
      !std::all_of(position->begin(), position->end(), [](const json& x) { return x.is_number(); }))
    throw InputError(where, "a control point needs \"position\": [x, y, z] (numbers)");
  return Vec3((*position)[0].get<double>(), (*position)[1].get<double>(), (*position)[2].get<double>());
}

// A string member, or `otherwise` when absent; InputError when it is not a string.
std::string text_member(const json& object, const char* key, const char* otherwise, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) return otherwise;
  if (!it->is_string()) throw InputError(fmt::format("{}/{}", where, key), "expected a string");
  return it->get<std::string>();
}

}  // namespace

MarkupsPoints read_markups(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "cannot read the markups file");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_markups(text, file.string());
}

MarkupsPoints parse_markups(const std::string& text, const std::string& label) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {  // a syntax error, or a number out of range (out_of_range.406)
    throw InputError(label, fmt::format("not a 3D Slicer markups file (.mrk.json): {}", e.what()));
  }
  const auto markups = root.find("markups");
  if (!root.is_object() || markups == root.end() || !markups->is_array() || markups->empty() ||
      !(*markups)[0].is_object())
    throw InputError(label,
                     "not a 3D Slicer markups file: no \"markups\" list (save a line or a point list from "
                     "Slicer's Markups module as .mrk.json)");
  const json& markup = (*markups)[0];
  const std::string at = label + ": /markups/0";
  MarkupsPoints out;
  out.type = text_member(markup, "type", "", at);
  out.frame = text_member(markup, "coordinateSystem", "LPS", at);  // the schema's default
  if (out.frame != "LPS" && out.frame != "RAS")
    throw InputError(label + ": /markups/0/coordinateSystem",
                     fmt::format("\"{}\" is not a frame mtled knows: \"LPS\" or \"RAS\"", out.frame));
  const std::string units = text_member(markup, "coordinateUnits", "mm", at);
  const double to_metres = units == "mm" ? 1e-3 : units == "um" ? 1e-6 : 0.0;
  if (to_metres == 0.0)
    throw InputError(label + ": /markups/0/coordinateUnits",
                     fmt::format("\"{}\" is not a unit mtled reads: \"mm\" or \"um\"", units));
  const auto control = markup.find("controlPoints");
  if (control != markup.end() && control->is_array())
    for (std::size_t i = 0; i < control->size(); ++i) {
      const json& point = (*control)[i];
      const std::string where = fmt::format("{}/controlPoints/{}", at, i);
      if (!point.is_object() || text_member(point, "positionStatus", "defined", where) != "defined") continue;
      out.points.push_back({text_member(point, "label", "", where), to_metres * markup_position(point, where)});
    }
  return out;
}

}  // namespace mtled
