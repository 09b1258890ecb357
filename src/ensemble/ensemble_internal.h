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

/* For other stages that run ensembles (src/calibrate/). */
/**
 * Take the exclusive lock DIR/@p name as karst_ensemble_run takes DIR/.ensemble.lock (flock,
 * pid written in it, refused with KARST_EBUSY: "DIR is in use by another karst WHAT (pid
 * ...)"); release with karst_i_ensemble_unlock, which removes the file.
 */
karst_error_t karst_i_ensemble_lock(karst_ctx_t *ctx, const char *dir, const char *name,
                                    const char *what, int *fd, char **path);
void karst_i_ensemble_unlock(int fd, char *path);
/** Ranks of the MPI world (1 without MPI or when @p use_mpi is 0); this rank in @p rank. */
int karst_i_ensemble_world(int use_mpi, int *rank);
/** The worst (largest) error code over the @p ranks ranks; a collective call under MPI. */
karst_error_t karst_i_ensemble_agree(int ranks, karst_error_t local);
/**
 * A directory's key file: @p path must hold exactly @p want (a re-run must be the same run),
 * or is created with it. A different key is KARST_EINVAL: "PATH: this directory holds HOLDS
 * (key: ...); use another output directory or ADVICE".
 */
karst_error_t karst_i_key_file(karst_ctx_t *ctx, const char *path, const char *want,
                               const char *holds, const char *advice);
/** Remove a file or a directory tree; 0 on success (a missing path is a success). */
int karst_i_remove_tree(const char *path);
/** Remove the hidden leftovers of a killed run in @p dir: names starting with '.' that contain
 *  ".tmp." (karst_temp_name, member temporaries). */
karst_error_t karst_i_remove_stale_temporaries(karst_ctx_t *ctx, const char *dir);

#endif
