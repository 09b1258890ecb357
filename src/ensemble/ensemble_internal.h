/* Helpers shared by the files of src/ensemble/ (and read by src/report/). */
#ifndef KARST_ENSEMBLE_INTERNAL_H
#define KARST_ENSEMBLE_INTERNAL_H

#include "karst/ensemble.h"

/** "a/b", malloc'ed (NULL when out of memory). */
char *karst_i_path_join(const char *a, const char *b);
/** Directory name of member @p index: at least four digits, zero-padded ("0007"). */
void karst_i_member_name(char out[32], karst_int_t index);
/** "index,seed,<metric names...>" for @p h, malloc'ed into @p out. */
karst_error_t karst_i_metrics_header(karst_ctx_t *ctx, const karst_ensemble_hooks_t *h, char **out);
/**
 * Whether this process may run given what a launcher says: @p size receives
 * karst_ensemble_launcher_size(); KARST_EUNSUPPORTED (with a message) when the
 * launcher started more than one process and @p built_with_mpi is 0, since
 * every process would then compute every member and race on the same files.
 * A parameter rather than KARST_HAVE_MPI so that tests check both builds.
 */
karst_error_t karst_i_ensemble_launcher_check(karst_ctx_t *ctx, int built_with_mpi, int *size);

#endif
