// The cell fields of result.vtu (io/src/derived_fields.cpp) on a homogeneous deformation, which the shape functions
// reproduce exactly: every tet's value must be the closed form of the neo-Hookean law as defined (W = mu/2 (I1_bar - 3)
// + (J - 1)^2 / D, so sigma = mu/J dev(B_bar) + 2 (J - 1)/D I), not what the material plugin computes.
#include "mtled/io/derived_fields.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "mtled/io/run_outputs.hpp"
#include "test_support.hpp"

namespace mtled {
namespace {

TEST(DerivedFields, HomogeneousStretchGivesTheLawsClosedFormInEveryTet) {
  const double mu = 722.0, D = 4.02684e-5;
  auto model = std::make_unique<test::Discretised>(test::box_mesh(Vec3(0.01, 0.01, 0.01), 4, 4, 4, 0.25, 3),
                                                   test::make<ShapeFunctions>("mls", json::object()),
                                                   std::vector<std::shared_ptr<const Material>>{test::make<Material>(
                                                       "neo_hookean", {{"mu", mu}, {"D", D}, {"density", 1000.0}})},
                                                   Discretisation::Options{});
  // Uniaxial stretch a along x with lateral contraction b: u = (F - I) X at the nodes.
  const double a = 1.2, b = 0.93;
  const Vec3 stretch(a, b, b);
  std::vector<double> u(3 * static_cast<std::size_t>(model->discretisation.node_count()));
  for (Index i = 0; i < model->discretisation.node_count(); ++i)
    for (int c = 0; c < 3; ++c)
      u[3 * static_cast<std::size_t>(i) + c] = (stretch[c] - 1.0) * model->discretisation.nodes()[i][c];

  const double J = a * b * b;
  const double pressure = 2.0 * (J - 1.0) / D;
  const double deviatoric = mu / J * std::pow(J, -2.0 / 3.0) * (a * a - b * b);  // sigma_xx - sigma_yy
  const Vec3 sigma(pressure + 2.0 / 3.0 * deviatoric, pressure - deviatoric / 3.0, pressure - deviatoric / 3.0);

  std::vector<std::string> names;
  for (const auto& field : derived_fields()) names.push_back(field.name);
  const auto fields = cell_fields(model->kernel, u, names);
  ASSERT_EQ(fields.size(), 4u);
  const auto tets = static_cast<std::size_t>(model->discretisation.mesh().tet_count());
  // The fit reproduces linear fields to round-off amplified by its conditioning (about 1e-12 here).
  const double strain_tolerance = 1e-10, stress_tolerance = 1e-10 * std::abs(pressure);
  for (std::size_t t = 0; t < tets; ++t) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        const double green = r == c ? 0.5 * (stretch[r] * stretch[r] - 1.0) : 0.0;
        const double cauchy = r == c ? sigma[r] : 0.0;
        ASSERT_NEAR(fields[0].values[9 * t + 3 * r + c], green, strain_tolerance) << "green_strain, tet " << t;
        ASSERT_NEAR(fields[1].values[9 * t + 3 * r + c], cauchy, stress_tolerance) << "cauchy_stress, tet " << t;
      }
    ASSERT_NEAR(fields[2].values[t], std::abs(deviatoric), stress_tolerance) << "von_mises_stress, tet " << t;
    ASSERT_NEAR(fields[3].values[t], J, strain_tolerance) << "jacobian, tet " << t;
  }
}

// The scene's cell_data choices are the derived fields: each one is accepted, anything else is refused naming them.
TEST(DerivedFields, TheOutputSectionOffersExactlyTheDerivedFields) {
  const SceneSection output = output_section();
  json choices = json::array();
  for (const auto& field : derived_fields()) choices.push_back(field.name);
  const json schema = output.declaration->to_json_schema();
  EXPECT_EQ(schema["properties"]["cell_data"]["items"]["enum"], choices) << schema["properties"]["cell_data"].dump();
  for (const auto& field : derived_fields()) {
    EXPECT_TRUE(field.components == 1 || field.components == 9) << field.name;
    EXPECT_FALSE(field.unit.empty()) << field.name;
  }
}

}  // namespace
}  // namespace mtled
