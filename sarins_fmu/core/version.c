#include "smath.h"

#include "sarins_core.h"

int sarins_core_abi(void) { return SARINS_CORE_ABI; }
