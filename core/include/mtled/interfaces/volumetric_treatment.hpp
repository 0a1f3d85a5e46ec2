#pragma once
// How the volume change enters the stress. Without a treatment (the scene has no "volumetric" block) every
// integration point uses its own deformation gradient F, as the paper does. A treatment replaces the kernel's
// force evaluation by its own passes over the integration points, built from the kernel's two primitives:
// F at every point (ForceKernel::deformation_gradients) and nodal forces from a weighted first Piola-Kirchhoff stress
// at every point (ForceKernel::scatter_stresses), with the discretisation's thread team for its own per-node loops.
// F-bar, B-bar and three-field (u-p-J) schemes are treatments of this kind (FEBio's three-field solid domain is one).
#include <span>

#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled {

class ForceKernel;

class VolumetricTreatment {
 public:
  static constexpr Category category = Category::volumetric;
  virtual ~VolumetricTreatment();

  // Once, as `kernel` is built: the treatment may keep per-point and per-node storage for its discretisation (an
  // instance serves one kernel).
  virtual void setup(const ForceKernel& kernel) = 0;
  // Internal nodal forces f = dE/du for nodal parameters u (3 per node), E the treatment's discrete strain
  // energy. Returns -1, or the lowest-numbered integration point whose F is inadmissible (f is then incomplete).
  virtual Index internal_forces(const ForceKernel& kernel, std::span<const double> u, std::span<double> f) = 0;
  // Whether the treatment sums over ranges of points (below): an engine that shares the points between processes
  // then has each compute its own points' contributions; otherwise every process computes the whole sum (the same
  // answer, not divided).
  virtual bool sums_over_ranges() const { return false; }
  // The contributions of the integration points of `ranges` only (every node of f written), each point's stress
  // as in the whole sum: its averages over every point they involve, inside the ranges or not. Returns -1, or the
  // lowest-numbered inadmissible point among those evaluated. The default throws std::logic_error.
  virtual Index internal_forces(const ForceKernel& kernel, std::span<const double> u, std::span<double> f,
                                std::span<const PointRange> ranges);
  // The integration points whose deformation gradients that evaluation computes: their supports are the nodes of u
  // it reads (an engine brings those to each process). The default: every point.
  virtual std::vector<PointRange> points_read(const ForceKernel& kernel, std::span<const PointRange> ranges);
  // E(u); NaN when some F is inadmissible.
  virtual double strain_energy(const ForceKernel& kernel, std::span<const double> u) = 0;
  // The deformation gradient each integration point's stress is computed from in the forces (F-bar's F_bar),
  // for outputs that show the stress the body carries. Returns -1, or the lowest-numbered inadmissible point. The
  // default: each point's own F.
  virtual Index stress_deformation_gradients(const ForceKernel& kernel, std::span<const double> u, std::span<Mat3> F);
};

}  // namespace mtled
