/* The MPI calls of ensembles and calibrations (src/ensemble/ensemble.c), loaded on first use.
 *
 * Open MPI and what it brings (libopen-rte, libopen-pal, hwloc, libevent, libudev...) cost every
 * karst process about 5 ms at start-up (measured on the 2-core project machine: an empty program
 * linked with -lmpi starts in 8 ms, without it in 3 ms), though only a run under mpirun needs MPI.
 * So libkarst is not linked with it: the few calls karst makes live in a plugin, libkarst_mpi.so
 * (src/ensemble/mpi_plugin.c, linked with MPI), built and installed next to libkarst, which
 * karst_i_mpi_load opens with dlopen when a launcher started the process (or when the process
 * already holds MPI, initialised by a program that embeds libkarst). */
#ifndef KARST_MPI_API_INTERNAL_H
#define KARST_MPI_API_INTERNAL_H

#include "karst/common.h"

/** File name of the plugin, in libkarst's own directory. */
#define KARST_I_MPI_PLUGIN "libkarst_mpi.so"
/** The plugin's one exported symbol: a function returning its table. */
#define KARST_I_MPI_ENTRY "karst_i_mpi_plugin_api"
/** Plugin interface version: the table's layout; a plugin of another version is refused. */
#define KARST_I_MPI_API_VERSION 1

/** The MPI calls karst makes, on MPI_COMM_WORLD; each returns MPI's error code (0: success). */
typedef struct {
  int version; /* KARST_I_MPI_API_VERSION */
  int (*initialized)(int *flag);
  int (*finalized)(int *flag);
  int (*init_thread_funneled)(int *provided);
  int (*finalize)(void);
  int (*size)(int *size);
  int (*rank)(int *rank);
  int (*max_int)(int in, int *out);                   /* MPI_Allreduce, MPI_MAX */
  int (*sum_long_long)(long long in, long long *out); /* MPI_Allreduce, MPI_SUM */
} karst_i_mpi_api_t;

/**
 * Open the plugin once per process (thread-safe); later calls return the first call's result.
 * @return the table, or NULL with the reason (dlopen's, or a version mismatch) in @p why.
 */
const karst_i_mpi_api_t *karst_i_mpi_load(char *why, size_t why_size);

/** The table if the plugin is already open, else NULL (never opens it). */
const karst_i_mpi_api_t *karst_i_mpi_loaded(void);

#endif
