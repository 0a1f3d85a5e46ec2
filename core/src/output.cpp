#include "mtled/output.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <sstream>

#include "mtled/errors.hpp"

namespace fs = std::filesystem;

namespace mtled {

namespace {
const char* const kOutputs[] = {"summary.json", "result.vtu", "series.pvd", "needle.csv", "reactions.csv",
                                "histograms.svg", "compare.json"};

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

void write_vtu(std::ostream& out, const TetMesh& mesh, std::span<const double> displacement,
               const std::vector<CellField>& cell_fields) {
  const std::size_t n = mesh.points.size();
  const std::size_t cells = mesh.tets.size();
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
      << "<UnstructuredGrid>\n"
      << fmt::format("<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n, cells);
  out << "<PointData Vectors=\"displacement\">\n"
      << "<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i)
    out << fmt::format("{:.17g} {:.17g} {:.17g}\n", displacement[3 * i], displacement[3 * i + 1], displacement[3 * i + 2]);
  out << "</DataArray>\n<DataArray type=\"Int32\" Name=\"region\" format=\"ascii\">\n";
  std::vector<int> point_region(n, std::numeric_limits<int>::max());
  for (std::size_t t = 0; t < cells; ++t)
    for (Index v : mesh.tets[t]) point_region[v] = std::min(point_region[v], static_cast<int>(mesh.tet_region[t]));
  for (std::size_t i = 0; i < n; ++i) out << point_region[i] << '\n';
  out << "</DataArray>\n</PointData>\n<CellData>\n<DataArray type=\"Int32\" Name=\"region\" format=\"ascii\">\n";
  for (std::size_t t = 0; t < cells; ++t) out << mesh.tet_region[t] << '\n';
  out << "</DataArray>\n";
  for (const auto& field : cell_fields) {
    out << fmt::format("<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">\n",
                       field.name, field.components);
    for (std::size_t t = 0; t < cells; ++t) {
      for (int c = 0; c < field.components; ++c)
        out << fmt::format("{:.10g}{}", field.values[t * field.components + c], c + 1 == field.components ? '\n' : ' ');
    }
    out << "</DataArray>\n";
  }
  out << "</CellData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const auto& p : mesh.points) out << fmt::format("{:.17g} {:.17g} {:.17g}\n", p[0], p[1], p[2]);
  out << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const auto& tet : mesh.tets) out << fmt::format("{} {} {} {}\n", tet[0], tet[1], tet[2], tet[3]);
  out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t t = 0; t < cells; ++t) out << 4 * (t + 1) << '\n';
  out << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t t = 0; t < cells; ++t) out << "10\n";
  out << "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
}

}  // namespace mtled
