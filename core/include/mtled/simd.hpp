#pragma once
// The instruction sets the vectorised kernels (the force kernel, the material laws' stress_batch) run on. One
// binary carries each kernel compiled for every instruction set of its architecture (x86: AVX-512, AVX2, SSE4
// and a portable baseline) and picks the best one the CPU has at run time (Google Highway's dispatch).
#include <string>
#include <vector>

namespace mtled::simd {

// The instruction set in use: "avx512", "avx2", "sse4", "baseline", ...
std::string current();
// The ones this CPU and this build share, best first; "baseline" is always last.
std::vector<std::string> available();
// Restricts every kernel of this process to `name` (one of available()), or back to the best with "best";
// throws InputError naming the choices otherwise. For comparisons and tests: the answers agree to round-off.
void use(const std::string& name);

}  // namespace mtled::simd
