/* The MPI plugin loaded on first use (src/ensemble/mpi_api_internal.h). */
#include "ensemble/mpi_api_internal.h"

#include <pthread.h>
#include <stdio.h>

#include "core/library_internal.h"

static pthread_once_t once = PTHREAD_ONCE_INIT;
static const karst_i_mpi_api_t *loaded;
static char load_error[1024]; /* why the load failed; empty when it succeeded */

static void load(void) {
  /* Global: Open MPI's own components, which it opens later, resolve MPI's symbols. */
  loaded = karst_i_plugin_table(KARST_I_MPI_PLUGIN, KARST_I_MPI_ENTRY, 1, KARST_I_MPI_API_VERSION,
                                load_error, sizeof load_error);
}

const karst_i_mpi_api_t *karst_i_mpi_load(char *why, size_t why_size) {
  if (pthread_once(&once, load) != 0)
    snprintf(load_error, sizeof load_error, "pthread_once failed");
  if (!loaded && why && why_size > 0) snprintf(why, why_size, "%s", load_error);
  return loaded;
}

const karst_i_mpi_api_t *karst_i_mpi_loaded(void) {
  return loaded;
}
