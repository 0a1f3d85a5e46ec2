#pragma once
// Small helpers the study's parts share.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "mtled/json.hpp"

namespace mtled::study {

inline const char* const kAxes[] = {"x", "y", "z"};

// "x", "y", "z" (or "ux", ...) -> 0, 1, 2; -1 otherwise.
inline int axis_index(const std::string& name) {
  for (int k = 0; k < 3; ++k)
    if (name == kAxes[k] || name == std::string("u") + kAxes[k]) return k;
  return -1;
}

inline std::string value_text(const json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

// The file's JSON, or null when it is missing or unreadable (a run that died before writing it).
inline json read_json_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return json();
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return json();
  }
}

inline double number_or_nan(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : NAN;
}

inline std::string number_text(double v, const char* format = "{:.6g}") {
  return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : std::string();
}

inline json number_json(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

}  // namespace mtled::study
