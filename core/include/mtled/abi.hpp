#pragma once
// The build fingerprint: everything that must agree between the kernel and a plugin for C++ objects to
// cross the boundary safely. It is expanded in each translation unit that includes this header, so a plugin
// carries the values it was compiled with and the kernel compares them with its own (plugin_catalog.cpp).
#include <Eigen/Core>
#include <fmt/core.h>
#include <nlohmann/json.hpp>
#include <spdlog/version.h>

#include <string>
#include <vector>

#include "mtled/version.hpp"

#ifndef MTLED_PLUGIN_ABI_VERSION
// A test defines this to build a plugin that claims another ABI and must be refused.
#define MTLED_PLUGIN_ABI_VERSION MTLED_ABI_VERSION
#endif

#define MTLED_ABI_STR2(x) #x
#define MTLED_ABI_STR(x) MTLED_ABI_STR2(x)

#if defined(__clang__)
#define MTLED_ABI_COMPILER "clang-" MTLED_ABI_STR(__clang_major__)
#elif defined(__GNUC__)
#define MTLED_ABI_COMPILER "gcc-" MTLED_ABI_STR(__GNUC__)
#else
#define MTLED_ABI_COMPILER "unknown"
#endif

#if defined(_GLIBCXX_USE_CXX11_ABI)
#define MTLED_ABI_LIBSTDCXX MTLED_ABI_STR(_GLIBCXX_USE_CXX11_ABI)
#else
#define MTLED_ABI_LIBSTDCXX "none"
#endif

#if defined(_GLIBCXX_DEBUG)
#define MTLED_ABI_DEBUG_CONTAINERS "1"
#else
#define MTLED_ABI_DEBUG_CONTAINERS "0"
#endif

#if defined(EIGEN_VECTORIZE_AVX512)
#define MTLED_ABI_EIGEN_SIMD "avx512"
#elif defined(EIGEN_VECTORIZE_AVX)
#define MTLED_ABI_EIGEN_SIMD "avx"
#elif defined(EIGEN_VECTORIZE_SSE2)
#define MTLED_ABI_EIGEN_SIMD "sse2"
#elif defined(EIGEN_VECTORIZE)
#define MTLED_ABI_EIGEN_SIMD "other"
#else
#define MTLED_ABI_EIGEN_SIMD "none"
#endif

// `key=value;` pairs. The ABI version travels separately (first field of the handshake).
#define MTLED_BUILD_FINGERPRINT                                                                             \
  "compiler=" MTLED_ABI_COMPILER ";libstdcxx_cxx11_abi=" MTLED_ABI_LIBSTDCXX                               \
  ";debug_containers=" MTLED_ABI_DEBUG_CONTAINERS ";pointer_bytes=" MTLED_ABI_STR(__SIZEOF_POINTER__)      \
  ";eigen=" MTLED_ABI_STR(EIGEN_WORLD_VERSION) "." MTLED_ABI_STR(EIGEN_MAJOR_VERSION) "." MTLED_ABI_STR(    \
      EIGEN_MINOR_VERSION) ";eigen_max_align_bytes=" MTLED_ABI_STR(EIGEN_MAX_ALIGN_BYTES)                   \
  ";eigen_max_static_align_bytes=" MTLED_ABI_STR(EIGEN_MAX_STATIC_ALIGN_BYTES)                             \
  ";eigen_simd=" MTLED_ABI_EIGEN_SIMD ";nlohmann_json=" MTLED_ABI_STR(NLOHMANN_JSON_VERSION_MAJOR) "."      \
      MTLED_ABI_STR(NLOHMANN_JSON_VERSION_MINOR) ";spdlog=" MTLED_ABI_STR(SPDLOG_VER_MAJOR) "." MTLED_ABI_STR( \
          SPDLOG_VER_MINOR) ";fmt=" MTLED_ABI_STR(FMT_VERSION)

namespace mtled {

// The kernel's own fingerprint (compiled into libmtled_core).
const char* kernel_build_fingerprint();

// Human-readable list of the fields that differ: "eigen_simd: plugin avx, kernel sse2". Empty if equal.
std::vector<std::string> fingerprint_differences(const std::string& plugin, const std::string& kernel);

}  // namespace mtled
