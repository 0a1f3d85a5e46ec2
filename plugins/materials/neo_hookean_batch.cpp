// The neo-Hookean law's stress_batch() (neo_hookean_law-inl.h with one SIMD lane per integration point), for every
// instruction set Highway targets; mtled/law/stress_batch-inl.h says how.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "neo_hookean_batch.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include "mtled/law/stress_batch-inl.h"  // before the law

#include "neo_hookean_law-inl.h"

MTLED_LAW_STRESS_BATCH(NeoHookeanLaw, neo_hookean_stress_batch)
#if HWY_ONCE
MTLED_LAW_STRESS_BATCH_DISPATCH(NeoHookeanLaw, neo_hookean_stress_batch)
#endif
