#pragma once
// What the hyperelastic plugins of the paper's eq. (1) share on the host: their P-wave modulus and the
// declarations of the parameters every one of them has (mu, D, density), so that their docs, units and ranges are
// written once. The laws' shared arithmetic is in hyperelastic-inl.h.
#include "hyperelastic-inl.h"
#include "mtled/parameters.hpp"

namespace mtled::hyperelastic {

// lambda + 2 mu = K + 4 mu / 3 of a law whose small-strain shear modulus is mu and volumetric term `penalty`.
inline double p_wave_modulus(double shear_modulus, const VolumetricPenalty& penalty) {
  return penalty.two_over_D + 4.0 * shear_modulus / 3.0;
}

// The parameters every law here declares, "mu" (Pa), "D" (1/Pa) and "density" (kg/m^3), read with
// Parameters::read<Moduli>().
struct Moduli {
  double mu = 0.0;
  double D = 0.0;
  double density = 0.0;
};
void declare_shear_modulus(ComponentDeclaration& declaration);
void declare_compressibility(ComponentDeclaration& declaration);
void declare_density(ComponentDeclaration& declaration);

}  // namespace mtled::hyperelastic
