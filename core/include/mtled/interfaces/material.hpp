#pragma once
#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled {

// A hyperelastic constitutive law in the Total Lagrangian form: second Piola-Kirchhoff stress S(F) and
// strain energy W(F) per unit reference volume. Implementations must be thread-safe and must refuse
// (return false / NaN) an inadmissible F: J = det F <= 0 or non-finite entries, never hide it with |J|.
class Material {
 public:
  static constexpr Category category = Category::material;
  virtual ~Material();

  virtual double density() const = 0;  // kg/m^3
  // lambda + 2 mu of the material linearised at F = I (Pa): the dilatational wave speed for the stable step.
  virtual double p_wave_modulus() const = 0;
  virtual bool stress(const Mat3& F, Mat3& S) const noexcept = 0;
  virtual double energy(const Mat3& F) const noexcept = 0;
};

}  // namespace mtled
