/* Atomic file output: temporary file + rename (include/karst/io.h). */
#include "karst/io.h"

#include <errno.h>
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
