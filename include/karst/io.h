/**
 * @file io.h
 * @brief File output that never leaves a half-written file: write to a
 *        temporary name beside the target, then rename.
 */
#ifndef KARST_IO_H
#define KARST_IO_H

#include <stdio.h>

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct karst_atomic_file {
  char *path;     /**< final name */
  char *tmp_path; /**< temporary name in the same directory */
  FILE *fp;       /**< open on tmp_path while writing */
} karst_atomic_file_t;

/** Open a temporary file beside @p path for writing ("w" or "wb"). */
karst_error_t karst_atomic_open(karst_ctx_t *ctx, karst_atomic_file_t *f, const char *path,
                                const char *mode);
/** Flush, close and rename onto the final name. On failure the temporary file is removed. */
karst_error_t karst_atomic_commit(karst_ctx_t *ctx, karst_atomic_file_t *f);
/** Close and remove the temporary file (safe to call after a failed commit, or twice). */
void karst_atomic_abort(karst_atomic_file_t *f);

/**
 * A temporary name beside @p path (same directory, so rename is atomic):
 * "<dir>/.<base>.tmp.<pid>.<counter>". Caller frees.
 */
char *karst_temp_name(const char *path);
/** Rename @p tmp onto @p path, removing @p tmp on failure. */
karst_error_t karst_rename_into_place(karst_ctx_t *ctx, const char *tmp, const char *path);

/** Write @p s as a JSON string literal with the escapes JSON requires (NULL: null). */
void karst_json_string(FILE *fp, const char *s);

/** Create directory @p dir and its parents (like mkdir -p). */
karst_error_t karst_mkdir_p(karst_ctx_t *ctx, const char *dir);

#ifdef __cplusplus
}
#endif
#endif
