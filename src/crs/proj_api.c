/* PROJ loaded on first use (src/crs/proj_api_internal.h). */
#include "crs/proj_api_internal.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "core/library_internal.h"

#ifndef KARST_PROJ_SONAME
#error "KARST_PROJ_SONAME (the soname of libproj, e.g. libproj.so.25) is set by CMakeLists.txt"
#endif

karst_i_proj_t karst_i_proj;

static pthread_once_t once = PTHREAD_ONCE_INIT;
static char load_error[512]; /* why the load failed; empty when it succeeded */

static void load(void) {
  static const char *const names[] = {KARST_I_PROJ_FUNCTIONS(KARST_I_SYMBOL_NAME)};
  void *syms[sizeof names / sizeof *names];
  if (karst_i_library_open(KARST_PROJ_SONAME, 0, names, syms, sizeof names / sizeof *names,
                           load_error, sizeof load_error) != 0)
    return;
  size_t i = 0;
  /* dlsym returns void *; POSIX guarantees it converts to a function pointer. */
#define KARST_I_PROJ_SET(name) memcpy(&karst_i_proj.name, &syms[i++], sizeof(void *));
  KARST_I_PROJ_FUNCTIONS(KARST_I_PROJ_SET)
#undef KARST_I_PROJ_SET
}

karst_error_t karst_i_proj_load(karst_ctx_t *ctx) {
  if (pthread_once(&once, load) != 0)
    return karst_set_error(ctx, KARST_ENOTIMPL, "cannot load PROJ (%s)", KARST_PROJ_SONAME);
  if (load_error[0])
    return karst_set_error(ctx, KARST_ENOTIMPL,
                           "coordinate systems other than UTM and WGS 84 need PROJ, which could "
                           "not be loaded: %s (Debian: apt-get install libproj25)",
                           load_error);
  return KARST_SUCCESS;
}
