#pragma once
// A run's displacement sampled on an image grid: the field image-guided surgery uses (the pre-operative image moved
// to where the tissue is). Two directions, as ITK and 3D Slicer distinguish them:
//  - forward: at each voxel centre X of the reference body, u(X), where the material there goes (x = X + u(X));
//  - resampling: at each voxel centre x of the deformed body, d(x) = X - x with X + u(X) = x: the displacement a
//    resampling transform (ITK's, Slicer's) adds to an output point to find where to read the reference image.
// u is the run's interpolated nodal displacement carried to the point with MLS (MlsTransfer). Inside is decided by
// the background tets (reference ones for forward, moved ones for resampling). Outside the field is zero, or
// (extend_outside) the value at the nearest voxel inside fading to zero over a distance the user sets.
#include <array>
#include <cstdint>
#include <vector>

#include "mtled/io/image.hpp"  // VoxelGrid
#include "mtled/io/large_buffer.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/types.hpp"

namespace mtled {

enum class FieldDirection { forward, resampling };

struct GridField {
  LargeVector<Vec3> values;        // one per voxel (m), zero outside the body
  LargeVector<char> inside_body;   // one per voxel: 1 where the voxel's centre is inside the body
  std::int64_t inside = 0;         // voxels inside the (reference or moved) body
  std::int64_t overlapping = 0;    // resampling: voxels inside more than one moved tet (the body folded there)
  std::int64_t not_converged = 0;  // resampling: voxels whose X + u(X) = x was not solved to the tolerance
  std::vector<std::int64_t> not_converged_voxels;  // resampling: those voxels (storage indices), in order
  double largest_residual = 0.0;                   // resampling: the largest |X + u(X) - x| left (m)
};

struct BodyState {
  const std::vector<Vec3>& nodes;                 // reference positions (m)
  const std::vector<std::array<Index, 4>>& tets;  // background tets
  const std::vector<Vec3>& displacement;          // interpolated displacement at the nodes (m)
};

// The field on `grid` (in the body's frame). Resampling solves X + u(X) = x by Newton's method (u's MLS gradient) from
// the moved tet's linear map, to `tolerance` (m).
GridField displacement_on_grid(const BodyState& body, const VoxelGrid& grid, FieldDirection direction,
                               PluginCatalog& catalog, double tolerance = 1e-9);

// Outside the body, each voxel takes the value of its nearest voxel inside, times s(t) = 1 - 3 t^2 + 2 t^3 of
// t = distance / `decay` (m): continuous at the surface, smooth, zero from `decay` on. The nearest voxel is exact (the
// Euclidean distance transform with its sites, one pass per index axis). x + d(x) stays one-to-one outside while
// `decay` exceeds 1.5 times the largest value at the surface (the largest slope of s is 1.5). Returns that largest
// value (m).
double extend_outside(const VoxelGrid& grid, double decay, GridField& field);

}  // namespace mtled
