/* Atomic file output: temporary file + rename (include/karst/io.h). */
#include "karst/io.h"

#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static atomic_uint temp_counter;

char *karst_temp_name(const char *path) {
  const char *slash = strrchr(path, '/');
  size_t dirlen = slash ? (size_t)(slash - path + 1) : 0;
  const char *base = slash ? slash + 1 : path;
  size_t n = strlen(path) + 64;
  char *t = malloc(n);
  if (!t) return NULL;
  snprintf(t, n, "%.*s.%s.tmp.%ld.%u", (int)dirlen, path, base, (long)getpid(),
           atomic_fetch_add(&temp_counter, 1u));
  return t;
}

karst_error_t karst_atomic_open(karst_ctx_t *ctx, karst_atomic_file_t *f, const char *path,
                                const char *mode) {
  memset(f, 0, sizeof *f);
  f->path = strdup(path);
  f->tmp_path = karst_temp_name(path);
  if (!f->path || !f->tmp_path) {
    karst_atomic_abort(f);
    return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  }
  f->fp = fopen(f->tmp_path, mode);
  if (!f->fp) {
    int e = errno;
    karst_atomic_abort(f);
    return karst_set_error(ctx, KARST_EIO, "%s: cannot write: %s", path, strerror(e));
  }
  return KARST_SUCCESS;
}

karst_error_t karst_rename_into_place(karst_ctx_t *ctx, const char *tmp, const char *path) {
  if (rename(tmp, path) != 0) {
    int e = errno;
    remove(tmp);
    return karst_set_error(ctx, KARST_EIO, "%s: cannot rename into place: %s", path, strerror(e));
  }
  return KARST_SUCCESS;
}

karst_error_t karst_atomic_commit(karst_ctx_t *ctx, karst_atomic_file_t *f) {
  karst_error_t err = KARST_SUCCESS;
  int bad = ferror(f->fp);
  if (fclose(f->fp) != 0) bad = 1;
  f->fp = NULL;
  if (bad) {
    err = karst_set_error(ctx, KARST_EIO, "%s: write failed: %s", f->path, strerror(errno));
    remove(f->tmp_path);
  } else {
    err = karst_rename_into_place(ctx, f->tmp_path, f->path);
  }
  free(f->path);
  free(f->tmp_path);
  f->path = f->tmp_path = NULL;
  return err;
}

void karst_atomic_abort(karst_atomic_file_t *f) {
  if (f->fp) fclose(f->fp);
  if (f->tmp_path) remove(f->tmp_path);
  free(f->path);
  free(f->tmp_path);
  memset(f, 0, sizeof *f);
}

karst_error_t karst_mkdir_p(karst_ctx_t *ctx, const char *dir) {
  char *p = strdup(dir);
  if (!p) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", dir);
  for (char *s = p + 1;; s++) {
    if (*s == '/' || *s == '\0') {
      char c = *s;
      *s = '\0';
      if (mkdir(p, 0777) != 0 && errno != EEXIST) {
        int e = errno;
        karst_error_t err = karst_set_error(ctx, KARST_EIO, "%s: cannot create directory: %s", p, strerror(e));
        free(p);
        return err;
      }
      *s = c;
      if (c == '\0') break;
    }
  }
  struct stat st;
  int ok = stat(dir, &st) == 0 && S_ISDIR(st.st_mode);
  free(p);
  if (!ok) return karst_set_error(ctx, KARST_EIO, "%s: not a directory", dir);
  return KARST_SUCCESS;
}

/* File sets: the outputs of one run, committed together. */

void karst_fileset_init(karst_fileset_t *fs) { memset(fs, 0, sizeof *fs); }

static karst_error_t fileset_push(karst_ctx_t *ctx, karst_fileset_t *fs, char *path, char *tmp) {
  if (fs->n == fs->cap) {
    int cap = fs->cap ? 2 * fs->cap : 8;
    char **p = realloc(fs->path, (size_t)cap * sizeof *p);
    if (p) fs->path = p;
    char **t = p ? realloc(fs->tmp_path, (size_t)cap * sizeof *t) : NULL;
    if (t) fs->tmp_path = t;
    if (!p || !t) {
      free(path);
      free(tmp);
      return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    }
    fs->cap = cap;
  }
  fs->path[fs->n] = path;
  fs->tmp_path[fs->n] = tmp;
  fs->n++;
  return KARST_SUCCESS;
}

/**
 * Add member @p path of @p fs, written by the caller to @p tmp (or to
 * karst_temp_name(path) when @p tmp is NULL); *@p tmp_out gets that name.
 * @return KARST_SUCCESS or KARST_ENOMEM. Time complexity: amortised O(|path|).
 */
karst_error_t karst_fileset_add(karst_ctx_t *ctx, karst_fileset_t *fs, const char *path,
                                const char *tmp, const char **tmp_out) {
  char *p = strdup(path);
  char *t = tmp ? strdup(tmp) : karst_temp_name(path);
  if (!p || !t) {
    free(p);
    free(t);
    return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  }
  karst_error_t err = fileset_push(ctx, fs, p, t);
  if (!err && tmp_out) *tmp_out = t;
  return err;
}

/**
 * Add @p path as a stale member of @p fs: removed on commit (restored if the
 * commit fails), so a file of a previous set that the new set lacks does not
 * survive beside it. @return KARST_SUCCESS or KARST_ENOMEM. O(|path|).
 */
karst_error_t karst_fileset_add_stale(karst_ctx_t *ctx, karst_fileset_t *fs, const char *path) {
  char *p = strdup(path);
  if (!p) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  return fileset_push(ctx, fs, p, NULL);
}

/** Remove every temporary of @p fs and empty it. O(members). */
void karst_fileset_abort(karst_fileset_t *fs) {
  for (int i = 0; i < fs->n; i++) {
    if (fs->tmp_path[i]) remove(fs->tmp_path[i]);
    free(fs->path[i]);
    free(fs->tmp_path[i]);
  }
  free(fs->path);
  free(fs->tmp_path);
  karst_fileset_init(fs);
}

/**
 * Commit @p fs: first check that every temporary exists and hard-link each
 * existing final file to a backup name, then rename the temporaries into
 * place (and remove stale members) in the order they were added. When a step
 * fails, the members already replaced get their previous versions back from
 * the backups (or are removed when there was none, or it could not be linked:
 * the previous set then loses that file rather than mixing versions), the
 * temporaries are removed, and the error names the member. The last member is
 * renamed last, so a reader that sees it sees the whole new set.
 *
 * @return KARST_SUCCESS, KARST_EIO (message names the file), KARST_ENOMEM.
 * Time complexity: O(members) file-system operations.
 */
karst_error_t karst_fileset_commit(karst_ctx_t *ctx, karst_fileset_t *fs) {
  karst_error_t err = KARST_SUCCESS;
  int n = fs->n, done = 0;
  char **bak = calloc((size_t)(n > 0 ? n : 1), sizeof *bak);
  if (!bak) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
    goto cleanup;
  }
  for (int i = 0; i < n; i++) {
    struct stat st;
    if (fs->tmp_path[i] && stat(fs->tmp_path[i], &st) != 0) {
      int e = errno;
      err = karst_set_error(ctx, KARST_EIO, "%s: its temporary %s is missing: %s", fs->path[i],
                            fs->tmp_path[i], strerror(e));
      goto cleanup;
    }
    if (lstat(fs->path[i], &st) != 0 || !S_ISREG(st.st_mode)) continue;
    if (!(bak[i] = karst_temp_name(fs->path[i]))) {
      err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", fs->path[i]);
      goto cleanup;
    }
    if (link(fs->path[i], bak[i]) != 0) {
      free(bak[i]);
      bak[i] = NULL;
    }
  }
  for (; done < n; done++) {
    int i = done;
    int bad = fs->tmp_path[i] ? rename(fs->tmp_path[i], fs->path[i]) != 0
                              : (remove(fs->path[i]) != 0 && errno != ENOENT);
    if (bad) {
      int e = errno;
      err = karst_set_error(ctx, KARST_EIO,
                            "%s: cannot %s: %s (the files of its set already replaced were put back)", fs->path[i],
                            fs->tmp_path[i] ? "rename into place" : "remove", strerror(e));
      break;
    }
  }
  if (!err) /* renamed: nothing for karst_fileset_abort to remove */
    for (int i = 0; i < n; i++) {
      free(fs->tmp_path[i]);
      fs->tmp_path[i] = NULL;
    }
  if (err) /* undo members 0 .. done-1, newest first */
    for (int i = done - 1; i >= 0; i--) {
      if (bak[i]) {
        if (rename(bak[i], fs->path[i]) == 0) {
          free(bak[i]);
          bak[i] = NULL;
        }
      } else if (fs->tmp_path[i]) {
        remove(fs->path[i]);
      }
    }
cleanup:
  if (bak)
    for (int i = 0; i < n; i++)
      if (bak[i]) {
        remove(bak[i]);
        free(bak[i]);
      }
  free(bak);
  karst_fileset_abort(fs); /* removes the temporaries not renamed */
  return err;
}

karst_error_t karst_check_writable(karst_ctx_t *ctx, const char *path) {
  if (!path || !*path) return karst_set_error(ctx, KARST_EINVAL, "no output file name given");
  const char *slash = strrchr(path, '/');
  char *dir = slash ? strndup(path, slash == path ? 1 : (size_t)(slash - path)) : strdup(".");
  if (!dir) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  karst_error_t err = KARST_SUCCESS;
  struct stat st;
  if (stat(dir, &st) != 0) {
    int e = errno;
    err = e == ENOENT
              ? karst_set_error(ctx, KARST_EIO, "%s: cannot write: directory '%s' does not exist",
                                path, dir)
              : karst_set_error(ctx, KARST_EIO, "%s: cannot write: directory '%s': %s", path, dir,
                                strerror(e));
  } else if (!S_ISDIR(st.st_mode)) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot write: '%s' is not a directory", path, dir);
  } else if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot write: it is a directory", path);
  } else {
    char *probe = karst_temp_name(path);
    int fd = probe ? open(probe, O_WRONLY | O_CREAT | O_EXCL, 0666) : -1;
    if (!probe) {
      err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
    } else if (fd < 0) {
      int e = errno;
      err = karst_set_error(ctx, KARST_EIO, "%s: cannot write in directory '%s': %s", path, dir,
                            strerror(e));
    } else {
      close(fd);
      remove(probe);
    }
    free(probe);
  }
  free(dir);
  return err;
}

char *karst_temp_name_ext(const char *path) {
  const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
  const char *ext = dot && (!slash || dot > slash) ? dot : "";
  char *base = karst_temp_name(path);
  char *t = base ? malloc(strlen(base) + strlen(ext) + 1) : NULL;
  if (t) {
    strcpy(t, base);
    strcat(t, ext);
  }
  free(base);
  return t;
}
