#include "mtled/simd.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <hwy/highway.h>
#include <hwy/targets.h>

#include <cctype>
#include <cstdint>

#include "mtled/errors.hpp"

namespace mtled::simd {
namespace {

// The targets this build compiled (HWY_TARGETS) and the CPU supports, best (lowest bit) first.
std::vector<std::int64_t> targets() {
  const std::int64_t available = static_cast<std::int64_t>(HWY_TARGETS) & hwy::SupportedTargets();
  std::vector<std::int64_t> out;
  for (int bit = 0; bit < 63; ++bit)
    if (available & (std::int64_t{1} << bit)) out.push_back(std::int64_t{1} << bit);
  return out;
}

std::string name_of(std::int64_t target) {
  switch (target) {
    case HWY_AVX3: return "avx512";
    case HWY_AVX3_DL: return "avx512-dl";
    case HWY_AVX2: return "avx2";
    case HWY_SSE4: return "sse4";
    case HWY_SSSE3: return "ssse3";
    case HWY_EMU128:
    case HWY_SCALAR: return "baseline";
    default: {
      std::string name = hwy::TargetName(target);
      for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return name;
    }
  }
}

}  // namespace

std::string current() {
  const auto list = targets();
  return list.empty() ? "baseline" : name_of(list.front());
}

std::vector<std::string> available() {
  std::vector<std::string> names;
  for (std::int64_t target : targets())
    if (names.empty() || names.back() != name_of(target)) names.push_back(name_of(target));
  return names;
}

void use(const std::string& name) {
  if (name == "best") {
    hwy::SetSupportedTargetsForTest(0);
    return;
  }
  for (std::int64_t target : targets())
    if (name_of(target) == name) {
      hwy::SetSupportedTargetsForTest(target);
      return;
    }
  throw InputError("--simd", fmt::format("\"{}\" is not an instruction set this CPU and build share; choose one of: "
                                         "best, {}",
                                         name, fmt::join(available(), ", ")));
}

}  // namespace mtled::simd
