#pragma once
// Quantities derived from a state at the integration points, written as cell data of result.vtu (the scene's
// /output/cell_data names them). Each is one entry here: its name, components, unit and how it is computed from a
// point's deformation gradient and material; a new field is one more entry in derived_fields.cpp. Stresses come
// from the deformation gradient the forces use (a volumetric treatment's F_bar), strains from the point's own F.
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "mtled/force_kernel.hpp"
#include "mtled/io/output.hpp"

namespace mtled {

struct DerivedField {
  std::string name;
  int components = 1;  // 1, or 9 for a tensor (row-major)
  std::string unit;
  std::string doc;
  // Its value at one integration point with deformation gradient F (det F > 0) and material `material`.
  std::function<void(const Mat3& F, const Material& material, double* value)> compute;
  // A stress: F is the one the forces use (ForceKernel::stress_deformation_gradients), not the point's own.
  bool stress = false;
};

// Every field /output/cell_data may name, in the order the documentation lists them.
const std::vector<DerivedField>& derived_fields();

// The named fields per background tet, each averaged over the tet's integration points, for nodal parameters u.
std::vector<CellField> cell_fields(const ForceKernel& kernel, std::span<const double> u,
                                   const std::vector<std::string>& names);

}  // namespace mtled
