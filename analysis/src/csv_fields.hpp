#pragma once
// One line of a CSV file as its fields, each trimmed of blanks (no quoting: the files mtled reads and writes here
// hold numbers and plain labels).
#include <sstream>
#include <string>
#include <vector>

namespace mtled {

inline std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  std::string field;
  while (std::getline(in, field, ',')) {
    field.erase(0, field.find_first_not_of(" \t\r"));
    field.erase(field.find_last_not_of(" \t\r") + 1);
    fields.push_back(field);
  }
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

}  // namespace mtled
