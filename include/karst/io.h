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

/**
 * A set of files that replace each other's previous versions together (the
 * outputs of one run): each member is written to a temporary name first, and
 * karst_fileset_commit renames them all into place in the order they were
 * added, so the member added last (e.g. run.json) marks a complete set.
 */
typedef struct karst_fileset {
  int n, cap;
  char **path;     /**< final names, in commit order */
  char **tmp_path; /**< temporary names beside them; NULL: a stale member, removed on commit */
} karst_fileset_t;

/** An empty set. */
void karst_fileset_init(karst_fileset_t *fs);
/**
 * Add member @p path, to be written by the caller to a temporary name beside
 * it: @p tmp when not NULL (same directory, so the rename is atomic), else
 * karst_temp_name(path). *@p tmp_out (may be NULL) receives the name to write,
 * owned by the set.
 */
karst_error_t karst_fileset_add(karst_ctx_t *ctx, karst_fileset_t *fs, const char *path,
                                const char *tmp, const char **tmp_out);
/** Add @p path as a stale member: a file of a previous set that the new set removes on commit. */
karst_error_t karst_fileset_add_stale(karst_ctx_t *ctx, karst_fileset_t *fs, const char *path);
/**
 * Rename every temporary onto its final name, in order; on failure restore the
 * members already replaced from hard-link backups of their previous versions
 * (a member whose previous version cannot be linked is removed instead),
 * remove the remaining temporaries, and return the error. The set is empty
 * afterwards in both cases.
 */
karst_error_t karst_fileset_commit(karst_ctx_t *ctx, karst_fileset_t *fs);
/** Remove every temporary and empty the set (safe after a commit, or twice). */
void karst_fileset_abort(karst_fileset_t *fs);

/**
 * Check, before any work, that @p path can be written: its directory exists
 * and is a directory, @p path is not a directory, and a new file can be
 * created beside it (probed by creating and removing a temporary file, which
 * also catches read-only file systems). @return KARST_SUCCESS, KARST_EINVAL
 * (empty name), KARST_EIO with a message naming the path and the reason.
 */
karst_error_t karst_check_writable(karst_ctx_t *ctx, const char *path);

/**
 * karst_temp_name(path) followed by the extension of @p path
 * ("<dir>/.<base>.tmp.<pid>.<counter>.<ext>"), for writers that choose the
 * format by extension. Caller frees.
 */
char *karst_temp_name_ext(const char *path);

/** Write @p s as a JSON string literal with the escapes JSON requires (NULL: null). */
void karst_json_string(FILE *fp, const char *s);

/** Create directory @p dir and its parents (like mkdir -p). */
karst_error_t karst_mkdir_p(karst_ctx_t *ctx, const char *dir);

/**
 * @p to relative to the directory @p from_dir, both normalised (".", ".." and the symbolic
 * links of their directories resolved): from "out" to "build/../datasets/a.csv" gives
 * "../datasets/a.csv". Both directories must exist, the file need not. *@p out: caller frees.
 */
karst_error_t karst_path_relative(karst_ctx_t *ctx, const char *from_dir, const char *to,
                                  char **out);
/** @p path lexically normalised ("a/./b/../c" gives "a/c"; no file system access). Caller
 *  frees; NULL when out of memory. */
char *karst_path_normalize(const char *path);

#ifdef __cplusplus
}
#endif
#endif
