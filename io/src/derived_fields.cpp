#include "mtled/io/derived_fields.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mtled {

namespace {

Mat3 cauchy_stress(const Mat3& F, const Material& material) {
  Mat3 S = Mat3::Zero();
  material.stress(F, S);
  return F * S * F.transpose() / F.determinant();
}

void store(const Mat3& m, double* value) {
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) value[3 * a + b] = m(a, b);
}

}  // namespace

const std::vector<DerivedField>& derived_fields() {
  static const std::vector<DerivedField> fields = {
      {"green_strain", 9, "1", "E = (F^T F - I) / 2",
       [](const Mat3& F, const Material&, double* value) { store(0.5 * (F.transpose() * F - Mat3::Identity()), value); }},
      {"cauchy_stress", 9, "Pa", "sigma = F S F^T / J",
       [](const Mat3& F, const Material& material, double* value) { store(cauchy_stress(F, material), value); },
       true},
      {"von_mises_stress", 1, "Pa", "sqrt(3/2 s:s), s the deviator of the Cauchy stress",
       [](const Mat3& F, const Material& material, double* value) {
         const Mat3 cauchy = cauchy_stress(F, material);
         const Mat3 deviator = cauchy - cauchy.trace() / 3.0 * Mat3::Identity();
         *value = std::sqrt(1.5 * deviator.squaredNorm());
       },
       true},
      {"jacobian", 1, "1", "J = det F, the volume ratio",
       [](const Mat3& F, const Material&, double* value) { *value = F.determinant(); }},
  };
  return fields;
}

std::vector<CellField> cell_fields(const ForceKernel& kernel, std::span<const double> u,
                                   const std::vector<std::string>& names) {
  const Discretisation& model = kernel.discretisation();
  std::vector<CellField> out;
  const auto tets = static_cast<std::size_t>(model.mesh().tet_count());
  std::vector<Mat3> stress_gradients;  // computed for the first stress field named
  for (const auto& name : names) {
    const auto& all = derived_fields();
    const auto field = std::find_if(all.begin(), all.end(), [&](const DerivedField& f) { return f.name == name; });
    if (field == all.end()) throw std::invalid_argument("no derived field \"" + name + "\"");
    const auto components = static_cast<std::size_t>(field->components);
    CellField cells{name, field->components, std::vector<double>(tets * components, 0.0)};
    std::vector<int> count(tets, 0);
    std::vector<double> value(components);
    if (field->stress && stress_gradients.empty()) {
      stress_gradients.resize(static_cast<std::size_t>(model.points().count()));
      if (kernel.stress_deformation_gradients(u, stress_gradients) >= 0) stress_gradients.clear();
    }
    for (Index ip = 0; ip < model.points().count(); ++ip) {
      const bool own = !field->stress || stress_gradients.empty();  // empty: an inadmissible state, as written
      field->compute(own ? model.deformation_gradient(ip, u) : stress_gradients[static_cast<std::size_t>(ip)],
                     model.material(ip), value.data());
      const auto t = static_cast<std::size_t>(model.points().tets[ip]);
      ++count[t];
      for (std::size_t c = 0; c < components; ++c) cells.values[components * t + c] += value[c];
    }
    for (std::size_t t = 0; t < tets; ++t)
      for (std::size_t c = 0; c < components; ++c) cells.values[t * components + c] /= std::max(count[t], 1);
    out.push_back(std::move(cells));
  }
  return out;
}

}  // namespace mtled
