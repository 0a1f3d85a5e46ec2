// The arithmetic of a GPU backend's stress pass, run on the CPU: each shipped law's device code is
// mtled::scalar::stress_record (mtled/law/stress_record.hpp) on its law header, the same source as its plugin's
// one-point stress. A record holds F - I and must come back as w P = w F S with the plugin's S, or zeros and false
// where F is inadmissible. P is formed in the same order as F * S, so the two agree to a few roundings of |w F S|.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "material_test_support.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/law/one_point.hpp"
#include "mtled/law/stress_record.hpp"
#include "neo_hookean_law-inl.h"
#include "ogden_law-inl.h"
#include "test_support.hpp"

namespace mtled {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

template <class Law>
void expect_records_match(const Law& law, const Material& material, const std::string& name) {
  SCOPED_TRACE(name);
  const double weight = 2.5e-9;  // a tet of 2.5 mm^3
  auto deformations = test::admissible_deformations();
  deformations.push_back({"identity", Mat3::Identity()});
  for (const auto& [what, deformation] : deformations) {
    SCOPED_TRACE(what);
    double record[kDeviceRecord] = {};
    for (int c = 0; c < 9; ++c) record[c] = deformation(c / 3, c % 3) - (c / 3 == c % 3 ? 1.0 : 0.0);
    Mat3 F;  // as the device reads it back: I + (F - I), which may round
    for (int c = 0; c < 9; ++c) F(c / 3, c % 3) = c / 3 == c % 3 ? 1.0 + record[c] : record[c];
    ASSERT_TRUE(scalar::stress_record(law, weight, record));
    Mat3 S;
    ASSERT_TRUE(material.stress(F, S));
    const Mat3 P = weight * (F * S);
    const double scale = std::max(P.cwiseAbs().maxCoeff(), weight * material.p_wave_modulus() * kEpsilon);
    for (int c = 0; c < 9; ++c) EXPECT_NEAR(record[c], P(c / 3, c % 3), 8 * kEpsilon * scale) << "entry " << c;
    EXPECT_EQ(record[9], 0.0);
  }
  for (const Mat3& refused : {Mat3(-Mat3::Identity()), Mat3(Vec3(1.0, 1.0, 0.0).asDiagonal()),
                              Mat3(Mat3::Constant(std::numeric_limits<double>::quiet_NaN()))}) {
    double record[kDeviceRecord];
    for (int c = 0; c < 9; ++c) record[c] = refused(c / 3, c % 3) - (c / 3 == c % 3 ? 1.0 : 0.0);
    record[9] = 7.0;
    EXPECT_FALSE(scalar::stress_record(law, weight, record));
    for (double value : record) EXPECT_EQ(value, 0.0);
  }
}

TEST(DeviceStressRecord, ShippedLawsGiveTheirPluginsStress) {
  expect_records_match(OgdenLaw(722.0, -1.3, 5.57738e-5),
                       *test::make<Material>("ogden", {{"mu", 722.0}, {"alpha", -1.3}, {"D", 5.57738e-5}}), "ogden");
  expect_records_match(NeoHookeanLaw(1000.0, 4.02684e-5),
                       *test::make<Material>("neo_hookean", {{"mu", 1000.0}, {"D", 4.02684e-5}}), "neo_hookean");
}

}  // namespace
}  // namespace mtled
