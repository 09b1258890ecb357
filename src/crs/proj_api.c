/* PROJ loaded on first use (src/crs/proj_api_internal.h). */
#include "crs/proj_api_internal.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#ifndef KARST_PROJ_SONAME
#error "KARST_PROJ_SONAME (the soname of libproj, e.g. libproj.so.25) is set by CMakeLists.txt"
#endif

karst_i_proj_t karst_i_proj;

static pthread_once_t once = PTHREAD_ONCE_INIT;
static char load_error[512]; /* why the load failed; empty when it succeeded */

static void load(void) {
  void *lib = dlopen(KARST_PROJ_SONAME, RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    const char *why = dlerror();
    snprintf(load_error, sizeof load_error, "%s", why ? why : "dlopen failed");
    return;
  }
  /* dlsym returns void *; POSIX guarantees it converts to a function pointer. */
#define KARST_I_PROJ_LOOKUP(name)                                                                  \
  {                                                                                                \
    void *sym = dlsym(lib, #name);                                                                 \
    if (!sym) {                                                                                    \
      snprintf(load_error, sizeof load_error, "%s has no function %s", KARST_PROJ_SONAME, #name);  \
      return;                                                                                      \
    }                                                                                              \
    memcpy(&karst_i_proj.name, &sym, sizeof sym);                                                  \
  }
  KARST_I_PROJ_FUNCTIONS(KARST_I_PROJ_LOOKUP)
#undef KARST_I_PROJ_LOOKUP
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
