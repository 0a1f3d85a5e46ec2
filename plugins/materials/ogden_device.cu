// The Ogden law's stress pass on an NVIDIA GPU (ogden_law-inl.h as device code), for a GPU backend.
#include "mtled/law/device_stress_pass.cuh"
#include "ogden_law-inl.h"

MTLED_LAW_DEVICE_STRESS_PASS(OgdenLaw, ogden_device_stress_pass)
