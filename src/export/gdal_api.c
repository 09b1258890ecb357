/* GDAL loaded on first use (src/export/gdal_api_internal.h). */
#include "export/gdal_api_internal.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "core/library_internal.h"

#ifndef KARST_GDAL_SONAME
#error "KARST_GDAL_SONAME (the soname of libgdal, e.g. libgdal.so.32) is set by CMakeLists.txt"
#endif

karst_i_gdal_t karst_i_gdal;

static pthread_once_t once = PTHREAD_ONCE_INIT;
static char load_error[512]; /* why the load failed; empty when it succeeded */

static void load(void) {
  static const char *const names[] = {KARST_I_GDAL_FUNCTIONS(KARST_I_SYMBOL_NAME)};
  void *syms[sizeof names / sizeof *names];
  if (karst_i_library_open(KARST_GDAL_SONAME, 0, names, syms, sizeof names / sizeof *names,
                           load_error, sizeof load_error) != 0)
    return;
  size_t i = 0;
  /* dlsym returns void *; POSIX guarantees it converts to a function pointer. */
#define KARST_I_GDAL_SET(name) memcpy(&karst_i_gdal.name, &syms[i++], sizeof(void *));
  KARST_I_GDAL_FUNCTIONS(KARST_I_GDAL_SET)
#undef KARST_I_GDAL_SET
}

karst_error_t karst_i_gdal_load(karst_ctx_t *ctx) {
  if (pthread_once(&once, load) != 0)
    return karst_set_error(ctx, KARST_ENOTIMPL, "cannot load GDAL (%s)", KARST_GDAL_SONAME);
  if (load_error[0])
    return karst_set_error(ctx, KARST_ENOTIMPL,
                           "GeoPackage export needs GDAL, which could not be loaded: %s "
                           "(Debian: apt-get install libgdal32)",
                           load_error);
  return KARST_SUCCESS;
}
