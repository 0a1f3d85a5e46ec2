#pragma once
// Buffers of hundreds of megabytes (a field on an image grid, its scratch). They are the kernel's own arrays
// (mtled/types.hpp): from 2 MiB up on transparent huge pages, one page fault per 2 MiB instead of per 4 KiB (on a
// virtual machine a fault costs microseconds: half a million of them took 4 of the 17 s of a 256^3 field); and
// unfilled on sizing, as by new T[n], so that the first touch of each page is the fill that follows, on every thread
// (large_vector() below), rather than a serial zeroing first. Fill what you size.
#include <cstddef>
#include <cstdint>

#include "mtled/types.hpp"

namespace mtled {

template <class T>
using LargeVector = UnfilledVector<T>;

// n copies of value, written on every thread (each thread first-touches its own pages).
template <class T>
LargeVector<T> large_vector(std::size_t n, const T& value) {
  LargeVector<T> out(n);
  const auto count = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < count; ++i) out[static_cast<std::size_t>(i)] = value;
  return out;
}

}  // namespace mtled
