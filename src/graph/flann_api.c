/* FLANN loaded on first use (src/graph/flann_api_internal.h). */
#include "graph/flann_api_internal.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "core/library_internal.h"

#ifndef KARST_FLANN_SONAME
#error "KARST_FLANN_SONAME (the soname of libflann, e.g. libflann.so.1.9) is set by CMakeLists.txt"
#endif

karst_i_flann_t karst_i_flann;

static pthread_once_t once = PTHREAD_ONCE_INIT;
static char load_error[512]; /* why the load failed; empty when it succeeded */

static void load(void) {
  static const char *const names[] = {
      KARST_I_FLANN_FUNCTIONS(KARST_I_SYMBOL_NAME) "DEFAULT_FLANN_PARAMETERS"};
  void *syms[sizeof names / sizeof *names];
  if (karst_i_library_open(KARST_FLANN_SONAME, 0, names, syms, sizeof names / sizeof *names,
                           load_error, sizeof load_error) != 0)
    return;
  karst_i_flann_t f;
  size_t i = 0;
  /* dlsym returns void *; POSIX guarantees it converts to a function pointer. */
#define KARST_I_FLANN_SET(name) memcpy(&f.name, &syms[i++], sizeof(void *));
  KARST_I_FLANN_FUNCTIONS(KARST_I_FLANN_SET)
#undef KARST_I_FLANN_SET
  f.defaults = syms[i];
  karst_i_flann = f;
}

karst_error_t karst_i_flann_load(karst_ctx_t *ctx) {
  if (pthread_once(&once, load) != 0)
    return karst_set_error(ctx, KARST_ENOTIMPL, "cannot load FLANN (%s)", KARST_FLANN_SONAME);
  if (load_error[0])
    return karst_set_error(ctx, KARST_ENOTIMPL,
                           "the FLANN neighbour search (sampling.knn: flann) needs FLANN, which "
                           "could not be loaded: %s (Debian: apt-get install libflann1.9; the "
                           "default sampling.knn: grid does not need it)",
                           load_error);
  return KARST_SUCCESS;
}
