#pragma once
// A run's displacement sampled on an image grid: the field image-guided surgery uses (the pre-operative image moved
// to where the tissue is). Two directions, as ITK and 3D Slicer distinguish them:
//  - forward: at each voxel centre X of the reference body, u(X), where the material there goes (x = X + u(X));
//  - resampling: at each voxel centre x of the deformed body, d(x) = X - x with X + u(X) = x: the displacement a
//    resampling transform (ITK's, Slicer's) adds to an output point to find where to read the reference image.
// u is the run's interpolated nodal displacement carried to the point with MLS (MlsTransfer). Inside is decided by
// the background tets (reference ones for forward, moved ones for resampling); outside the field is zero.
#include <array>
#include <cstdint>
#include <vector>

#include "mtled/io/image_write.hpp"  // VoxelGrid
#include "mtled/plugin_catalog.hpp"
#include "mtled/types.hpp"

namespace mtled {

enum class FieldDirection { forward, resampling };

struct GridField {
  std::vector<Vec3> values;        // one per voxel (m), zero outside the body
  std::int64_t inside = 0;         // voxels inside the (reference or moved) body
  std::int64_t overlapping = 0;    // resampling: voxels inside more than one moved tet (the body folded there)
  std::int64_t not_converged = 0;  // resampling: voxels whose X + u(X) = x was not solved to the tolerance
  double largest_residual = 0.0;   // resampling: the largest |X + u(X) - x| left (m)
};

struct BodyState {
  const std::vector<Vec3>& nodes;                 // reference positions (m)
  const std::vector<std::array<Index, 4>>& tets;  // background tets
  const std::vector<Vec3>& displacement;          // interpolated displacement at the nodes (m)
};

// The field on `grid` (in the body's frame). Resampling solves X + u(X) = x by Newton's method started from the
// moved tet's linear map, to `tolerance` (m).
GridField displacement_on_grid(const BodyState& body, const VoxelGrid& grid, FieldDirection direction,
                               PluginCatalog& catalog, double tolerance = 1e-9);

}  // namespace mtled
