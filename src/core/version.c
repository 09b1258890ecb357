#include "karst/common.h"

#ifndef KARST_VERSION_STRING
#define KARST_VERSION_STRING "0.0.0"
#endif

const char *karst_version(void) { return KARST_VERSION_STRING; }
