// An independent reader of mtled's displacement fields: ITK's. Reads FIELD as an image of 3-vectors, makes it an
// itk::DisplacementFieldTransform and maps each point of POINTS (one "x y z" per line, LPS millimetres, ITK's
// physical space) to OUT. NRRD goes through ITK's own reader (NrrdImageIO). NIfTI goes through the NIfTI reference
// library (nifti1_io, which ITK links): ITK 5.2, Debian 12's, reads intent DISPVECT as a scalar image (fixed in ITK
// 5.3, which then turns the RAS vectors to LPS as done here by hand).
//   itk_field_points FIELD POINTS OUT
#include <itkDisplacementFieldTransform.h>
#include <itkImageFileReader.h>
#include <itkImageRegionIteratorWithIndex.h>
#include <nifti1_io.h>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

namespace {

using Vector = itk::Vector<double, 3>;
using Field = itk::Image<Vector, 3>;

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

Field::Pointer read_nrrd(const std::string& file) {
  auto reader = itk::ImageFileReader<Field>::New();
  reader->SetFileName(file);
  reader->Update();
  return reader->GetOutput();
}

// NIfTI's RAS grid and vectors into ITK's LPS: x and y change sign.
Field::Pointer read_nifti(const std::string& file) {
  nifti_image* nim = nifti_image_read(file.c_str(), 1);
  if (nim == nullptr) throw std::runtime_error("nifti_image_read failed on " + file);
  if (nim->ndim != 5 || nim->nu != 3 || nim->intent_code != NIFTI_INTENT_DISPVECT || nim->datatype != DT_FLOAT32)
    throw std::runtime_error("not a float DISPVECT field with 3 components: " + file);
  const double flip[3] = {-1.0, -1.0, 1.0};
  Field::Pointer field = Field::New();
  Field::SizeType size = {{static_cast<itk::SizeValueType>(nim->nx), static_cast<itk::SizeValueType>(nim->ny),
                           static_cast<itk::SizeValueType>(nim->nz)}};
  field->SetRegions(Field::RegionType(size));
  const mat44& m = nim->sto_xyz;  // the sform (sform_code > 0): voxel index to RAS millimetres
  Field::DirectionType direction;
  Field::SpacingType spacing;
  Field::PointType origin;
  for (int c = 0; c < 3; ++c) {
    double length = 0.0;
    for (int r = 0; r < 3; ++r) length += static_cast<double>(m.m[r][c]) * m.m[r][c];
    spacing[c] = std::sqrt(length);
    for (int r = 0; r < 3; ++r) direction[r][c] = flip[r] * m.m[r][c] / spacing[c];
    origin[c] = flip[c] * m.m[c][3];
  }
  field->SetSpacing(spacing);
  field->SetDirection(direction);
  field->SetOrigin(origin);
  field->Allocate();
  const auto* data = static_cast<const float*>(nim->data);
  const std::size_t voxels = static_cast<std::size_t>(nim->nx) * nim->ny * nim->nz;
  for (itk::ImageRegionIteratorWithIndex<Field> it(field, field->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it) {
    const auto& index = it.GetIndex();
    const std::size_t v = index[0] + nim->nx * (index[1] + static_cast<std::size_t>(nim->ny) * index[2]);
    Vector value;
    for (int c = 0; c < 3; ++c) value[c] = flip[c] * data[c * voxels + v];  // one component volume after another
    it.Set(value);
  }
  nifti_image_free(nim);
  return field;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: itk_field_points FIELD POINTS OUT\n";
    return 2;
  }
  try {
    const std::string file = argv[1];
    const Field::Pointer field = ends_with(file, ".nrrd") ? read_nrrd(file) : read_nifti(file);
    auto transform = itk::DisplacementFieldTransform<double, 3>::New();
    transform->SetDisplacementField(field);
    std::ifstream in(argv[2]);
    std::ofstream out(argv[3]);
    itk::Point<double, 3> p;
    while (in >> p[0] >> p[1] >> p[2]) {
      const auto q = transform->TransformPoint(p);
      char line[128];
      std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", q[0], q[1], q[2]);
      out << line;
    }
    return out ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "itk_field_points: " << e.what() << "\n";
    return 1;
  }
}
