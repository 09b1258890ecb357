/**
 * @file fuzz_util.c
 * @brief Scratch files and a quiet context for the fuzz targets (fuzz_util.h).
 */
#include "fuzz_util.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char fuzz_dir[4096];

/* Removes the scratch directory and whatever the targets (or the readers) left in it. */
static void fuzz_cleanup(void) {
  if (!fuzz_dir[0]) {
    return;
  }
  DIR *d = opendir(fuzz_dir);
  if (d) {
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
      if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) {
        continue;
      }
      char p[8192];
      snprintf(p, sizeof p, "%s/%s", fuzz_dir, e->d_name);
      unlink(p);
    }
    closedir(d);
  }
  rmdir(fuzz_dir);
}

void karst_fuzz_ctx(karst_ctx_t *ctx) {
  karst_ctx_init(ctx);
  ctx->log = NULL;
}

karst_error_t karst_fuzz_report(const karst_ctx_t *ctx, karst_error_t err) {
  static int verbose = -1;
  if (verbose < 0) verbose = getenv("KARST_FUZZ_VERBOSE") != NULL;
  if (verbose) {
    if (err == KARST_SUCCESS) {
      fprintf(stderr, "  accepted\n");
    } else {
      fprintf(stderr, "  refused: %s: %s\n", karst_error_name(err), ctx->errmsg);
    }
  }
  return err;
}

const char *karst_fuzz_dir(void) {
  if (!fuzz_dir[0]) {
    const char *tmp = getenv("TMPDIR");
    snprintf(fuzz_dir, sizeof fuzz_dir, "%s/karst_fuzz_XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(fuzz_dir)) {
      perror("karst fuzz: mkdtemp");
      abort();
    }
    atexit(fuzz_cleanup);
  }
  return fuzz_dir;
}

const char *karst_fuzz_file(const char *name, const uint8_t *data, size_t size) {
  static char path[8192];
  snprintf(path, sizeof path, "%s/%s", karst_fuzz_dir(), name);
  FILE *f = fopen(path, "wb");
  if (!f || (size > 0 && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
    perror("karst fuzz: scratch file");
    abort();
  }
  return path;
}

char *karst_fuzz_cstr(const uint8_t *data, size_t size) {
  char *s = malloc(size + 1);
  if (!s) {
    abort();
  }
  if (size > 0) {
    memcpy(s, data, size);
  }
  s[size] = '\0';
  return s;
}
