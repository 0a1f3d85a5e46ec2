#include "hyperelastic.hpp"

namespace mtled::hyperelastic {

void declare_shear_modulus(ComponentDeclaration& declaration) {
  declaration.number("mu")
      .unit("Pa")
      .positive()
      .doc(
          "shear modulus of the undeformed material (the slope of shear stress over shear strain at F = I); "
          "Sylgard 527 gel: 722 Pa (the paper's Table 1)")
      .to<&Moduli::mu>();
}

void declare_compressibility(ComponentDeclaration& declaration) {
  declaration.number("D")
      .unit("1/Pa")
      .positive()
      .doc(
          "compressibility: the volumetric energy is (1/D)(J - 1)^2, so the bulk modulus is K = 2/D; for a "
          "Poisson's ratio nu, D = 3(1 - 2 nu)/(mu (1 + nu)) (nu = 0.49 and mu = 722 Pa give "
          "D = 5.57738e-5); a smaller D is stiffer in volume and shortens the stable time step")
      .to<&Moduli::D>();
}

void declare_density(ComponentDeclaration& declaration) {
  declaration.number("density")
      .unit("kg/m^3")
      .positive()
      .defaults(1000.0)
      .doc("mass density in the reference configuration (soft tissue and silicone gels: about 1000)")
      .to<&Moduli::density>();
}

}  // namespace mtled::hyperelastic
