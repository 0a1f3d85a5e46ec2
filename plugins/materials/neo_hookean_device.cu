// The neo-Hookean law's stress pass on an NVIDIA GPU (neo_hookean_law-inl.h as device code), for a GPU backend.
#include "mtled/law/device_stress_pass.cuh"
#include "neo_hookean_law-inl.h"

MTLED_LAW_DEVICE_STRESS_PASS(NeoHookeanLaw, neo_hookean_device_stress_pass)
