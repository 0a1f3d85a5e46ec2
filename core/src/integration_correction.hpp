#pragma once
// Variationally consistent integration's nodal corrections (Chen, Hillman, Rueter, IJNME 2013;
// Discretisation::Options::consistent_integration): the xi_I for which sum_p w_p (grad N_I + xi_I - mean over p's
// support of xi_J) equals the boundary integral of N_I n for every node I. Built once with the discretisation.
#include <vector>

#include "mtled/gradient_rows.hpp"
#include "mtled/mesh.hpp"
#include "mtled/support_rows.hpp"

namespace mtled {

// xi per node from the gradient rows at the integration points (weights w_p), the interpolation rows at the nodes
// (the boundary integral's quadrature) and the mesh's boundary faces.
std::vector<Vec3> integration_correction(const TetMesh& mesh, const GradientRows& rows,
                                         const SupportRows& interpolation, const std::vector<double>& weights);

}  // namespace mtled
