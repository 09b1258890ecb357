/* The one guarded way karst opens an input file (src/io/input_internal.h):
 * regular files only, a size cap per format, reads bounded by the file's size. */
#include "io/input_internal.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char *file_kind(mode_t m) {
  if (S_ISDIR(m)) return "a directory";
  if (S_ISFIFO(m)) return "a FIFO (named pipe)";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISSOCK(m)) return "a socket";
  return "not a regular file";
}

/* "64 MiB", "2 GiB" or a byte count. */
static void size_text(long long bytes, char *buf, size_t sz) {
  if (bytes >= (1LL << 30) && bytes % (1LL << 30) == 0)
    snprintf(buf, sz, "%lld GiB", bytes >> 30);
  else if (bytes >= (1LL << 20) && bytes % (1LL << 20) == 0)
    snprintf(buf, sz, "%lld MiB", bytes >> 20);
  else
    snprintf(buf, sz, "%lld bytes", bytes);
}

/* The checks on a stat() result shared by the functions below. */
static karst_error_t check_stat(karst_ctx_t *ctx, const char *path, const char *what,
                                long long max_bytes, const struct stat *st) {
  char lim[32];
  if (!S_ISREG(st->st_mode))
    return karst_set_error(ctx, KARST_EIO, "%s: is %s; the %s must be a regular file", path,
                           file_kind(st->st_mode), what);
  size_text(max_bytes, lim, sizeof lim);
  if ((long long)st->st_size > max_bytes)
    return karst_set_error(ctx, KARST_ERANGE,
                           "%s: the %s file is %lld bytes, more than the limit of %s", path, what,
                           (long long)st->st_size, lim);
  return KARST_SUCCESS;
}

karst_error_t karst_i_check_regular(karst_ctx_t *ctx, const char *path, const char *what,
                                    long long max_bytes) {
  struct stat st;
  if (!path || !*path) return karst_set_error(ctx, KARST_EINVAL, "no %s file name given", what);
  if (stat(path, &st) != 0)
    return karst_set_error(ctx, KARST_EIO, "%s: cannot open: %s", path, strerror(errno));
  return check_stat(ctx, path, what, max_bytes, &st);
}

karst_error_t karst_i_open_regular(karst_ctx_t *ctx, const char *path, const char *what,
                                   long long max_bytes, FILE **fp) {
  struct stat st;
  karst_error_t err;
  *fp = NULL;
  if ((err = karst_i_check_regular(ctx, path, what, max_bytes))) return err;
  FILE *f = fopen(path, "rb");
  if (!f) return karst_set_error(ctx, KARST_EIO, "%s: cannot open: %s", path, strerror(errno));
  /* The path may have been replaced between stat and fopen: check what was opened. */
  if (fstat(fileno(f), &st) != 0 || (err = check_stat(ctx, path, what, max_bytes, &st))) {
    fclose(f);
    return err ? err
               : karst_set_error(ctx, KARST_EIO, "%s: the %s must be a regular file", path, what);
  }
  *fp = f;
  return KARST_SUCCESS;
}

karst_error_t karst_i_read_regular(karst_ctx_t *ctx, const char *path, const char *what,
                                   long long max_bytes, unsigned char **data, size_t *len) {
  FILE *fp;
  struct stat st;
  karst_error_t err;
  *data = NULL;
  *len = 0;
  if ((err = karst_i_open_regular(ctx, path, what, max_bytes, &fp))) return err;
  if (fstat(fileno(fp), &st) != 0) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot read: %s", path, strerror(errno));
    fclose(fp);
    return err;
  }
  /* Room for the size stat() gave plus one byte, to notice a file that grew. */
  size_t cap = (size_t)st.st_size + 1, n = 0;
  unsigned char *buf = malloc(cap + 1);
  if (!buf) {
    fclose(fp);
    return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory reading the %s file (%lld bytes)",
                           path, what, (long long)st.st_size);
  }
  for (;;) {
    size_t got = fread(buf + n, 1, cap - n, fp);
    n += got;
    if (got == 0 || n < cap) {
      if (ferror(fp)) {
        err = karst_set_error(ctx, KARST_EIO, "%s: read error: %s", path, strerror(errno));
        goto fail;
      }
      if (feof(fp)) break;
      continue;
    }
    /* The file is larger than when it was opened: follow it up to the cap only. */
    if ((long long)n > max_bytes) {
      char lim[32];
      size_text(max_bytes, lim, sizeof lim);
      err = karst_set_error(ctx, KARST_ERANGE,
                            "%s: the %s file grew past the limit of %s while "
                            "being read",
                            path, what, lim);
      goto fail;
    }
    size_t ncap = cap * 2 > (size_t)max_bytes + 1 ? (size_t)max_bytes + 1 : cap * 2;
    unsigned char *nb = realloc(buf, ncap + 1);
    if (!nb) {
      err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory reading the %s file", path, what);
      goto fail;
    }
    buf = nb;
    cap = ncap;
  }
  fclose(fp);
  buf[n] = '\0';
  *data = buf;
  *len = n;
  return KARST_SUCCESS;
fail:
  fclose(fp);
  free(buf);
  return err;
}
