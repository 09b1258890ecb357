/* libkarst_mpi.so: the MPI calls of src/ensemble/ensemble.c (mpi_api_internal.h), the only code
 * of karst linked with MPI. Not part of libkarst: CMakeLists.txt builds it as a module next to
 * the library, which opens it with dlopen under mpirun. */
#include <mpi.h>

#include "ensemble/mpi_api_internal.h"

static int initialized(int *flag) {
  return MPI_Initialized(flag);
}
static int finalized(int *flag) {
  return MPI_Finalized(flag);
}
static int init_thread_funneled(int *provided) {
  return MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, provided);
}
static int finalize(void) {
  return MPI_Finalize();
}
static int size(int *n) {
  return MPI_Comm_size(MPI_COMM_WORLD, n);
}
static int rank(int *r) {
  return MPI_Comm_rank(MPI_COMM_WORLD, r);
}
static int max_int(int in, int *out) {
  return MPI_Allreduce(&in, out, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
}
static int sum_long_long(long long in, long long *out) {
  return MPI_Allreduce(&in, out, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
}

static const karst_i_mpi_api_t api = {KARST_I_MPI_API_VERSION,
                                      initialized,
                                      finalized,
                                      init_thread_funneled,
                                      finalize,
                                      size,
                                      rank,
                                      max_int,
                                      sum_long_long};

/* The entry point (KARST_I_MPI_ENTRY), the one symbol the module exports. */
__attribute__((visibility("default"))) const karst_i_mpi_api_t *karst_i_mpi_plugin_api(void);
const karst_i_mpi_api_t *karst_i_mpi_plugin_api(void) {
  return &api;
}
