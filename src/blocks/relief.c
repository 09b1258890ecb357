/* Relief images for the gradient-based warping of Paris et al. 2020, §4.3:
 * the displacement d(u, v) read from a greyscale image (PGM, P2 or P5,
 * 8 or 16 bits, or PNG through libpng), tiled periodically over a ground
 * size, sampled bilinearly, with its Lipschitz constant so that the warp can
 * keep the field's bound. Untrusted input: every size and value is checked
 * before it is used, and a malformed file gives a message naming it. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/blocks.h"

void karst_blocks_relief_destroy(karst_blocks_relief_t *r) {
  if (!r) return;
  free(r->v);
  memset(r, 0, sizeof *r);
}

/* PGM header tokens: whitespace and '#' comments between them (Netpbm). */
static int pgm_token(FILE *fp, char *buf, size_t n) {
  int c;
  size_t k = 0;
  for (;;) {
    c = fgetc(fp);
    if (c == '#') {
      while (c != EOF && c != '\n')
        c = fgetc(fp);
      continue;
    }
    if (c == EOF) return -1;
    if (c != ' ' && c != '\t' && c != '\n' && c != '\r') break;
  }
  while (c != EOF && c != ' ' && c != '\t' && c != '\n' && c != '\r' && c != '#') {
    if (k + 1 >= n) return -1;
    buf[k++] = (char)c;
    c = fgetc(fp);
  }
  buf[k] = '\0';
  if (c == '#') ungetc(c, fp);
  return 0;
}

static int pgm_uint(FILE *fp, long lo, long hi, long *out) {
  char t[32], *end;
  if (pgm_token(fp, t, sizeof t)) return -1;
  for (const char *p = t; *p; p++)
    if (*p < '0' || *p > '9') return -1;
  errno = 0;
  long v = strtol(t, &end, 10);
  if (errno || *end || v < lo || v > hi) return -1;
  *out = v;
  return 0;
}

static karst_error_t read_pgm(karst_ctx_t *ctx, FILE *fp, const char *path,
                              karst_blocks_relief_t *r) {
  char magic[4];
  long w, h, maxval;
  if (pgm_token(fp, magic, sizeof magic) || (strcmp(magic, "P2") && strcmp(magic, "P5")))
    return karst_set_error(ctx, KARST_EPARSE, "%s: not a PGM image (no P2 or P5 magic number)",
                           path);
  if (pgm_uint(fp, 1, KARST_BLOCKS_RELIEF_MAX_SIDE, &w) ||
      pgm_uint(fp, 1, KARST_BLOCKS_RELIEF_MAX_SIDE, &h))
    return karst_set_error(ctx, KARST_EPARSE,
                           "%s: PGM width and height must be integers from 1 to %d", path,
                           KARST_BLOCKS_RELIEF_MAX_SIDE);
  if (pgm_uint(fp, 1, 65535, &maxval))
    return karst_set_error(ctx, KARST_EPARSE, "%s: PGM maxval must be an integer from 1 to 65535",
                           path);
  int binary = magic[1] == '5';
  size_t n = (size_t)w * (size_t)h;
  r->v = malloc(n * sizeof *r->v);
  if (!r->v) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for %zu pixels", path, n);
  r->width = (int)w, r->height = (int)h;
  for (size_t i = 0; i < n; i++) {
    long v;
    if (binary) {
      int c0 = fgetc(fp), c1 = maxval > 255 ? fgetc(fp) : 0;
      if (c0 == EOF || c1 == EOF) {
        karst_blocks_relief_destroy(r);
        return karst_set_error(ctx, KARST_EPARSE, "%s: PGM data ends after %zu of %zu pixels", path,
                               i, n);
      }
      v = maxval > 255 ? (c0 << 8) | c1 : c0;
      if (v > maxval) {
        karst_blocks_relief_destroy(r);
        return karst_set_error(ctx, KARST_EPARSE, "%s: pixel %zu is %ld, above maxval %ld", path, i,
                               v, maxval);
      }
    } else if (pgm_uint(fp, 0, maxval, &v)) {
      karst_blocks_relief_destroy(r);
      return karst_set_error(ctx, KARST_EPARSE,
                             "%s: pixel %zu of %zu is missing or not an integer from 0 to %ld",
                             path, i, n, maxval);
    }
    r->v[i] = (float)((double)v / (double)maxval);
  }
  return KARST_SUCCESS;
}

typedef struct png_err {
  char msg[256];
} png_err_t;

static void on_png_error(png_structp png, png_const_charp msg) {
  png_err_t *e = png_get_error_ptr(png);
  snprintf(e->msg, sizeof e->msg, "%s", msg);
  png_longjmp(png, 1);
}
static void on_png_warning(png_structp png, png_const_charp msg) {
  (void)png, (void)msg;
}

static karst_error_t read_png(karst_ctx_t *ctx, FILE *fp, const char *path,
                              karst_blocks_relief_t *r) {
  png_err_t e = {""};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &e, on_png_error, on_png_warning);
  png_infop info = png ? png_create_info_struct(png) : NULL;
  float *volatile v = NULL;
  png_bytep volatile row = NULL;
  if (!png || !info) {
    png_destroy_read_struct(png ? &png : NULL, NULL, NULL);
    return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for the PNG reader", path);
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, NULL);
    free(v);
    free(row);
    return karst_set_error(ctx, KARST_EPARSE, "%s: not a readable PNG image (%s)", path,
                           e.msg[0] ? e.msg : "libpng error");
  }
  png_set_user_limits(png, KARST_BLOCKS_RELIEF_MAX_SIDE, KARST_BLOCKS_RELIEF_MAX_SIDE);
  png_init_io(png, fp);
  png_read_info(png, info);
  png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  int ct = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
  /* everything to 8- or 16-bit grey, without alpha */
  if (ct == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (ct == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (ct == PNG_COLOR_TYPE_RGB || ct == PNG_COLOR_TYPE_RGB_ALPHA || ct == PNG_COLOR_TYPE_PALETTE)
    png_set_rgb_to_gray_fixed(png, 1, -1, -1);
  if (ct & PNG_COLOR_MASK_ALPHA || png_get_valid(png, info, PNG_INFO_tRNS))
    png_set_strip_alpha(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  size_t rb = png_get_rowbytes(png, info);
  int d16 = png_get_bit_depth(png, info) == 16, ch = png_get_channels(png, info);
  if (rb < (size_t)w * (size_t)ch * (d16 ? 2 : 1)) png_error(png, "inconsistent row size");
  v = malloc((size_t)w * h * sizeof *v);
  row = malloc(rb);
  if (!v || !row) png_error(png, "out of memory");
  for (png_uint_32 y = 0; y < h; y++) {
    png_read_row(png, row, NULL);
    for (png_uint_32 x = 0; x < w; x++) {
      double g = d16 ? (double)((row[2 * ch * x] << 8) | row[2 * ch * x + 1]) / 65535.0
                     : (double)row[ch * x] / 255.0;
      v[(size_t)(h - 1 - y) * w + x] = (float)g; /* row 0 at the bottom, as the PGM reader */
    }
  }
  png_destroy_read_struct(&png, &info, NULL);
  free(row);
  r->v = v, r->width = (int)w, r->height = (int)h;
  return KARST_SUCCESS;
}

/**
 * Read a greyscale relief image (PGM P2/P5 or PNG, by content) into @p r,
 * values scaled to [0, 1]; rows are stored bottom up (row 0 at v = 0).
 * @return KARST_SUCCESS; KARST_EIO (cannot open); KARST_EPARSE (malformed,
 *         truncated, over KARST_BLOCKS_RELIEF_MAX_SIDE pixels a side);
 *         KARST_ENOMEM. Nothing is kept on failure.
 * Time complexity: O(pixels).
 */
karst_error_t karst_blocks_relief_load(karst_ctx_t *ctx, const char *path,
                                       karst_blocks_relief_t *r) {
  memset(r, 0, sizeof *r);
  FILE *fp = fopen(path, "rb");
  if (!fp)
    return karst_set_error(ctx, KARST_EIO, "%s: cannot open the relief image: %s", path,
                           strerror(errno));
  unsigned char sig[8] = {0};
  size_t got = fread(sig, 1, 8, fp);
  rewind(fp);
  karst_error_t err;
  if (got == 8 && !png_sig_cmp(sig, 0, 8))
    err = read_png(ctx, fp, path, r);
  else
    err = read_pgm(ctx, fp, path, r);
  fclose(fp);
  if (err) return err;
  /* Lipschitz constant of the bilinear interpolant in pixel units: the
   * largest difference of neighbouring pixels (periodic) */
  double L = 0;
  for (int y = 0; y < r->height; y++)
    for (int x = 0; x < r->width; x++) {
      double c = r->v[(size_t)y * r->width + x];
      double dx = fabs(r->v[(size_t)y * r->width + (x + 1) % r->width] - c);
      double dy = fabs(r->v[(size_t)((y + 1) % r->height) * r->width + x] - c);
      if (dx > L) L = dx;
      if (dy > L) L = dy;
    }
  r->lipschitz_px = L * sqrt(2.0);
  return KARST_SUCCESS;
}

/**
 * Bilinear value at (u, v) in pixel units, periodic in both directions.
 * Its Lipschitz constant is r->lipschitz_px (per pixel). O(1).
 */
double karst_blocks_relief_sample(const karst_blocks_relief_t *r, double u, double v) {
  double fu = floor(u), fv = floor(v), a = u - fu, b = v - fv;
  long x0 = (long)fmod(fu, r->width), y0 = (long)fmod(fv, r->height);
  if (x0 < 0) x0 += r->width;
  if (y0 < 0) y0 += r->height;
  long x1 = (x0 + 1) % r->width, y1 = (y0 + 1) % r->height;
  const float *p = r->v;
  double v00 = p[y0 * r->width + x0], v10 = p[y0 * r->width + x1];
  double v01 = p[y1 * r->width + x0], v11 = p[y1 * r->width + x1];
  return (1 - b) * ((1 - a) * v00 + a * v10) + b * ((1 - a) * v01 + a * v11);
}
