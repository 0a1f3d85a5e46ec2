#include "mtled/analysis/result_file.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>

#include "mtled/errors.hpp"
#include "mtled/json.hpp"

namespace fs = std::filesystem;

namespace mtled {

fs::path result_file_of(const fs::path& run) {
  std::error_code ec;
  if (!fs::exists(run, ec))
    throw InputError(run.string(), "no such run folder or result file");
  if (!fs::is_directory(run, ec)) return run;
  const fs::path file = run / "result.vtu";
  if (fs::exists(file, ec)) return file;
  std::string status;
  if (std::ifstream in(run / "summary.json"); in) {
    try {
      status = json::parse(in).value("status", "");
    } catch (const std::exception&) {
      status.clear();
    }
  }
  throw InputError(file.string(), status.empty() || status == "ok"
                                      ? "missing: not an mtled run folder, or its run did not finish"
                                      : fmt::format("missing: the run's summary.json says status \"{}\", so it wrote "
                                                    "no result",
                                                    status));
}

ResultField read_result_vtu(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "cannot read the result file (is this an mtled output folder?)");
  ResultField result;
  std::string line;
  int line_number = 0;
  std::vector<Vec3>* target = nullptr;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.rfind("<DataArray", 0) == 0) {
      const std::string tag = line.substr(0, line.find('>'));
      if (tag.find("Name=\"displacement\"") != std::string::npos) {
        target = &result.displacement;
      } else if (line.find("NumberOfComponents=\"3\"") != std::string::npos && line.find("Name=") == std::string::npos) {
        target = &result.points;
      } else {
        target = nullptr;
      }
      continue;
    }
    if (line.rfind("</DataArray", 0) == 0) {
      target = nullptr;
      continue;
    }
    if (target == nullptr) continue;
    std::istringstream values(line);
    Vec3 v;
    if (!(values >> v[0] >> v[1] >> v[2]))
      throw InputError(fmt::format("{}:{}", file.string(), line_number), "expected three numbers");
    target->push_back(v);
  }
  if (result.points.empty() || result.points.size() != result.displacement.size())
    throw InputError(file.string(), fmt::format("not an mtled result: {} points, {} displacements", result.points.size(),
                                                result.displacement.size()));
  return result;
}

}  // namespace mtled
