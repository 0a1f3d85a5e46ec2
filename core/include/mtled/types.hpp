#pragma once
#include <Eigen/Dense>
#include <cstdint>

namespace mtled {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// Node, integration-point and tet indices. 32 bits cover meshes far beyond what fits in memory here.
using Index = std::int32_t;

}  // namespace mtled
