/* Normalised and relative paths (include/karst/io.h). */
#include "karst/io.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

/* The absolute, normalised form of @p path whose directory exists (the file itself need not):
 * realpath of the directory, then the last component. Caller frees; NULL with errno set. */
static char *absolute(const char *path) {
  const char *slash = strrchr(path, '/');
  if (!slash) {
    char *dir = realpath(".", NULL);
    if (!dir) return NULL;
    if (strcmp(path, ".") == 0 || strcmp(path, "..") == 0 || !*path) {
      free(dir);
      return realpath(*path ? path : ".", NULL);
    }
    size_t n = strlen(dir) + strlen(path) + 2;
    char *out = malloc(n);
    if (out) snprintf(out, n, "%s/%s", strcmp(dir, "/") ? dir : "", path);
    free(dir);
    return out;
  }
  const char *base = slash + 1;
  if (!*base || strcmp(base, ".") == 0 || strcmp(base, "..") == 0) return realpath(path, NULL);
  size_t dl = (size_t)(slash - path);
  char *d = malloc(dl + 2);
  if (!d) return NULL;
  memcpy(d, path, dl);
  d[dl] = '\0';
  if (dl == 0) strcpy(d, "/");
  char *dir = realpath(d, NULL);
  free(d);
  if (!dir) return NULL;
  size_t n = strlen(dir) + strlen(base) + 2;
  char *out = malloc(n);
  if (out) snprintf(out, n, "%s/%s", strcmp(dir, "/") ? dir : "", base);
  free(dir);
  return out;
}

/**
 * The path of @p to relative to directory @p from_dir, both normalised ("." and ".."
 * resolved, symbolic links of their directories followed), e.g. from "out/report" to
 * "build/../datasets/x.csv": "../../datasets/x.csv". Both directories must exist; the file
 * @p to need not. "." when they are the same.
 * @param out receives a string the caller frees.
 * @return KARST_SUCCESS, KARST_EIO (a directory cannot be resolved; the message names it),
 *         KARST_ENOMEM.
 * Time complexity: O(length of the paths) plus the realpath calls.
 */
karst_error_t karst_path_relative(karst_ctx_t *ctx, const char *from_dir, const char *to,
                                  char **out) {
  *out = NULL;
  char *a = realpath(from_dir, NULL);
  if (!a)
    return karst_set_error(ctx, KARST_EIO, "%s: cannot resolve the directory: %s", from_dir,
                           strerror(errno));
  char *b = absolute(to);
  if (!b) {
    int e = errno;
    free(a);
    return karst_set_error(ctx, KARST_EIO, "%s: cannot resolve its directory: %s", to, strerror(e));
  }
  /* Longest common prefix of whole components. */
  size_t i = 0, last = 0;
  while (a[i] && a[i] == b[i]) {
    if (a[i] == '/') last = i;
    i++;
  }
  if ((!a[i] && (b[i] == '/' || !b[i])) || (!b[i] && a[i] == '/')) last = i;
  int ups = 0;
  if (strcmp(a, "/") != 0) /* from the root nothing is above */
    for (const char *p = a + last; *p; p++)
      if (*p == '/') ups++;
  const char *rest = b + last;
  while (*rest == '/')
    rest++;
  size_t n = 3 * (size_t)ups + strlen(rest) + 2;
  char *r = malloc(n);
  karst_error_t err = KARST_SUCCESS;
  if (!r) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  } else {
    r[0] = '\0';
    for (int k = 0; k < ups; k++)
      strcat(r, k + 1 < ups || *rest ? "../" : "..");
    strcat(r, rest);
    if (!r[0]) strcpy(r, ".");
    *out = r;
  }
  free(a);
  free(b);
  return err;
}

/**
 * @p path with "." components, repeated slashes and "name/.." pairs removed, by its text only
 * (no file system access, so symbolic links are not followed): "a/./b/../c//d" gives "a/c/d",
 * "../x/.." gives "..", "/.." gives "/". Caller frees; NULL when out of memory.
 * Time complexity: O(length of @p path).
 */
char *karst_path_normalize(const char *path) {
  size_t n = strlen(path);
  char *out = malloc(n + 2);
  if (!out) return NULL;
  int absolute = path[0] == '/';
  size_t len = 0; /* of out, without the leading '/' of an absolute path */
  char *o = out + absolute;
  for (const char *p = path; *p;) {
    while (*p == '/')
      p++;
    const char *e = p;
    while (*e && *e != '/')
      e++;
    size_t c = (size_t)(e - p);
    if (c == 0) break;
    if (c == 1 && p[0] == '.') {
      /* nothing */
    } else if (c == 2 && p[0] == '.' && p[1] == '.') {
      /* drop the previous component unless it is ".." itself (or nothing above the root) */
      size_t start = len;
      while (start > 0 && o[start - 1] != '/')
        start--;
      int prev_dotdot = len - start == 2 && o[start] == '.' && o[start + 1] == '.';
      if (len > 0 && !prev_dotdot)
        len = start > 0 ? start - 1 : 0;
      else if (!absolute) {
        if (len > 0) o[len++] = '/';
        o[len++] = '.', o[len++] = '.';
      }
    } else {
      if (len > 0) o[len++] = '/';
      memcpy(o + len, p, c);
      len += c;
    }
    p = e;
  }
  if (absolute) out[0] = '/';
  o[len] = '\0';
  if (!absolute && len == 0) strcpy(out, ".");
  return out;
}
