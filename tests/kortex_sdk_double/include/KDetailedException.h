#pragma once
// The Kortex SDK double: one header declares everything (kortex_sdk_double.h).
#include "kortex_sdk_double.h"
