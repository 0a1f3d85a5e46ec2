// The Mooney-Rivlin law's stress_batch(): mooney_rivlin_law-inl.h with one SIMD lane per integration point, compiled
// by Google Highway for every instruction set it targets and run on the best one the CPU has.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "mooney_rivlin_batch.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include "mtled/law/stress_batch-inl.h"  // before the law

#include "mooney_rivlin_law-inl.h"

MTLED_LAW_STRESS_BATCH(example::MooneyRivlinLaw, mooney_rivlin_stress_batch)
#if HWY_ONCE
MTLED_LAW_STRESS_BATCH_DISPATCH(example::MooneyRivlinLaw, mooney_rivlin_stress_batch)
#endif
