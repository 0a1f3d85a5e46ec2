#pragma once
// A run's output folder. Every file is written under a temporary name and renamed when complete, so the
// folder never holds a half-written file; files an earlier run left are removed first, so old and new
// results never mix.
#include <filesystem>
#include <fstream>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "mtled/mesh.hpp"

namespace mtled {

class OutputFolder {
 public:
  // Creates the folder; throws InputError when it cannot be created or written.
  explicit OutputFolder(std::filesystem::path folder);
  const std::filesystem::path& path() const { return folder_; }

  // Removes the files mtled writes (summary.json, result.vtu, series.pvd, steps/, *.csv, ...).
  void clear_previous_outputs() const;
  void write_file(const std::string& name, const std::function<void(std::ostream&)>& write) const;

  // A file filled during a run (history CSVs): rows go to NAME.partial; commit() renames it into place.
  class Stream {
   public:
    Stream() = default;
    Stream(std::filesystem::path final_path);
    std::ostream& out() { return out_; }
    void commit();
    bool is_open() const { return out_.is_open(); }

   private:
    std::filesystem::path final_path_;
    std::filesystem::path partial_path_;
    std::ofstream out_;
  };
  Stream open_stream(const std::string& name) const;

 private:
  std::filesystem::path folder_;
};

// Cell data of result.vtu: one tuple of `components` values per tet.
struct CellField {
  std::string name;
  int components = 1;
  std::vector<double> values;
};

// How result files store their arrays: binary, zlib-compressed and appended in base64 (VTK's default, about
// a third of the text's size), or ASCII text with full precision.
enum class VtuFormat { binary, ascii };

// The unit of result files' coordinates and displacements: metres (mtled's unit), or millimetres, the unit of
// 3D Slicer and of most medical images, so that a result loads on top of the image its mesh came from.
// Stresses and strains are unchanged (Pa, 1).
enum class LengthUnit { metre, millimetre };

struct VtuStyle {
  VtuFormat format = VtuFormat::binary;
  LengthUnit length_unit = LengthUnit::metre;
};

// An unstructured-grid VTK XML file readable by ParaView, VTK, meshio and 3D Slicer: the reference mesh
// with point data "displacement" and "region" and the given cell data. Doubles are written exactly in
// both formats. In millimetres the file says so in a string field "LENGTH_UNIT" ("mm"), which
// read_result_vtu honours.
void write_vtu(std::ostream& out, const TetMesh& mesh, std::span<const double> displacement,
               const std::vector<CellField>& cell_fields, const VtuStyle& style = {});

}  // namespace mtled
