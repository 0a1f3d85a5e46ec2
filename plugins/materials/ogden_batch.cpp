// The Ogden law's stress_batch() (ogden_law-inl.h with one SIMD lane per integration point), for every
// instruction set Highway targets; mtled/law/stress_batch-inl.h says how.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "ogden_batch.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include "mtled/law/stress_batch-inl.h"  // before the law

#include "ogden_law-inl.h"

MTLED_LAW_STRESS_BATCH(OgdenLaw, ogden_stress_batch)
#if HWY_ONCE
MTLED_LAW_STRESS_BATCH_DISPATCH(OgdenLaw, ogden_stress_batch)
#endif
