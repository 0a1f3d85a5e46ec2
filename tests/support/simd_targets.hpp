#pragma once
// Runs a check once per instruction set that both this CPU and the build's Highway dispatch support (x86:
// AVX-512, AVX2, SSE4, and the portable baseline that any CPU runs), with run-time dispatch forced to it, so
// that every vectorised path and the baseline are compared with the same reference. The forcing is global
// (libhwy's chosen target): it affects the plugins this process loaded too.
#include <hwy/highway.h>
#include <hwy/targets.h>

#include <cstdint>
#include <string>

namespace mtled::test {

template <class Check>
void for_each_simd_target(Check check) {
  const std::int64_t available = static_cast<std::int64_t>(HWY_TARGETS) & hwy::SupportedTargets();
  for (int bit = 0; bit < 63; ++bit) {
    const std::int64_t target = std::int64_t{1} << bit;
    if (!(available & target)) continue;
    hwy::SetSupportedTargetsForTest(target);
    check(std::string(hwy::TargetName(target)));
  }
  hwy::SetSupportedTargetsForTest(0);  // back to the CPU's own
}

}  // namespace mtled::test
