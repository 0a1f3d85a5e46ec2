#include "mtled/abi.hpp"

#include <map>
#include <sstream>

namespace mtled {

const char* kernel_build_fingerprint() { return MTLED_BUILD_FINGERPRINT; }

namespace {
std::map<std::string, std::string> parse_fingerprint(const std::string& text) {
  std::map<std::string, std::string> fields;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ';')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) {
      fields[item] = "";
    } else {
      fields[item.substr(0, eq)] = item.substr(eq + 1);
    }
  }
  return fields;
}
}  // namespace

std::vector<std::string> fingerprint_differences(const std::string& plugin, const std::string& kernel) {
  const auto p = parse_fingerprint(plugin);
  const auto k = parse_fingerprint(kernel);
  std::vector<std::string> differences;
  for (const auto& [key, value] : k) {
    const auto it = p.find(key);
    const std::string theirs = it == p.end() ? "(missing)" : it->second;
    if (theirs != value) differences.push_back(key + ": plugin " + theirs + ", kernel " + value);
  }
  for (const auto& [key, value] : p) {
    if (!k.count(key)) differences.push_back(key + ": plugin " + value + ", kernel (missing)");
  }
  return differences;
}

}  // namespace mtled
