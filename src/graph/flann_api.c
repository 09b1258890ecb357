/* FLANN loaded on first use (src/graph/flann_api_internal.h). */
#include "graph/flann_api_internal.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#ifndef KARST_FLANN_SONAME
#error "KARST_FLANN_SONAME (the soname of libflann, e.g. libflann.so.1.9) is set by CMakeLists.txt"
#endif

karst_i_flann_t karst_i_flann;

static pthread_once_t once = PTHREAD_ONCE_INIT;
static char load_error[512]; /* why the load failed; empty when it succeeded */

static void load(void) {
  void *lib = dlopen(KARST_FLANN_SONAME, RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    const char *why = dlerror();
    snprintf(load_error, sizeof load_error, "%s", why ? why : "dlopen failed");
    return;
  }
  karst_i_flann_t f;
  memset(&f, 0, sizeof f);
  /* dlsym returns void *; POSIX guarantees it converts to a function pointer. */
#define KARST_I_FLANN_LOOKUP(name)                                                                 \
  {                                                                                                \
    void *sym = dlsym(lib, #name);                                                                 \
    if (!sym) {                                                                                    \
      snprintf(load_error, sizeof load_error, "%s has no function %s", KARST_FLANN_SONAME, #name); \
      return;                                                                                      \
    }                                                                                              \
    memcpy(&f.name, &sym, sizeof sym);                                                             \
  }
  KARST_I_FLANN_FUNCTIONS(KARST_I_FLANN_LOOKUP)
#undef KARST_I_FLANN_LOOKUP
  f.defaults = dlsym(lib, "DEFAULT_FLANN_PARAMETERS");
  if (!f.defaults) {
    snprintf(load_error, sizeof load_error, "%s has no DEFAULT_FLANN_PARAMETERS",
             KARST_FLANN_SONAME);
    return;
  }
  karst_i_flann = f; /* all or nothing */
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
