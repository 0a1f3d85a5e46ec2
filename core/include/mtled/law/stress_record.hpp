#pragma once
// One integration point of a GPU backend's stress pass (device_stress_pass.hpp's records), written for the host and
// the device alike so that the CPU's tests check the arithmetic the device runs: record = F - I in, w F S out.
#include "mtled/law/arithmetic-inl.h"
#include "mtled/law/device_stress_pass.hpp"

namespace mtled::scalar {

// False, and the record zeroed, where F or its stress is inadmissible.
template <class Law>
MTLED_HOST_DEVICE inline bool stress_record(const Law& law, double weight, double* record) {
  Matrix3<double> F;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) F.m[i][k] = i == k ? 1.0 + record[3 * i + k] : record[3 * i + k];
  const LawStress<double> result = evaluate_stress(law, F);
  if (!result.admissible) {
    for (int c = 0; c < kDeviceRecord; ++c) record[c] = 0.0;
    return false;
  }
  double S[3][3];  // the whole of S from its upper triangle
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) S[i][j] = i <= j ? result.S.m[i][j] : result.S.m[j][i];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      record[3 * i + j] = weight * (F.m[i][0] * S[0][j] + F.m[i][1] * S[1][j] + F.m[i][2] * S[2][j]);
  return true;
}

}  // namespace mtled::scalar
