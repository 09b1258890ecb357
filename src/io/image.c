/* Greyscale images for the reliefs of the warping operator: PGM (Netpbm P2
 * and P5, parsed here) and PNG (through libpng), see include/karst/image.h. */
#include <png.h>
#include <setjmp.h>
#include <stdlib.h>
#include <string.h>

#include "karst/image.h"
#include "scenario/scenario_internal.h"

/* Rec. 709 luma weights of a colour sample. */
#define LUMA_R 0.2126
#define LUMA_G 0.7152
#define LUMA_B 0.0722

void karst_image_init(karst_image_t *img) {
  memset(img, 0, sizeof *img);
}

void karst_image_destroy(karst_image_t *img) {
  if (!img) return;
  free(img->v);
  memset(img, 0, sizeof *img);
}

static karst_error_t check_size(karst_ctx_t *ctx, const char *path, long long w, long long h) {
  if (w < 1 || h < 1)
    return karst_set_error(ctx, KARST_EPARSE, "%s: image of %lld x %lld pixels: both must be >= 1",
                           path, w, h);
  if (w > KARST_IMAGE_MAX_PIXELS || h > KARST_IMAGE_MAX_PIXELS || w * h > KARST_IMAGE_MAX_PIXELS)
    return karst_set_error(ctx, KARST_ERANGE,
                           "%s: image of %lld x %lld pixels exceeds the limit of %lld pixels", path,
                           w, h, KARST_IMAGE_MAX_PIXELS);
  return KARST_SUCCESS;
}

/* ---------------------------------------------------------------------- */
/* PGM                                                                     */
/* ---------------------------------------------------------------------- */

typedef struct {
  const unsigned char *b;
  size_t n, at;
  int line;
} cursor_t;

/* Skip whitespace and '#' comments (which run to the end of the line). */
static void skip_space(cursor_t *c) {
  while (c->at < c->n) {
    unsigned char ch = c->b[c->at];
    if (ch == '#') {
      while (c->at < c->n && c->b[c->at] != '\n')
        c->at++;
    } else if (ch == ' ' || ch == '\t' || ch == '\r' || ch == '\n' || ch == '\v' || ch == '\f') {
      if (ch == '\n') c->line++;
      c->at++;
    } else {
      break;
    }
  }
}

/* A decimal integer of at most 9 digits; -1 when there is none. */
static long long read_uint(cursor_t *c) {
  long long v = 0;
  int digits = 0;
  while (c->at < c->n && c->b[c->at] >= '0' && c->b[c->at] <= '9') {
    if (digits == 9) return -2; /* too long */
    v = 10 * v + (c->b[c->at] - '0');
    c->at++;
    digits++;
  }
  return digits ? v : -1;
}

static karst_error_t pgm_field(karst_ctx_t *ctx, const char *path, cursor_t *c, const char *what,
                               long long *out) {
  skip_space(c);
  long long v = read_uint(c);
  if (v == -2)
    return karst_set_error(ctx, KARST_EPARSE, "%s:%d: PGM header: %s has more than 9 digits", path,
                           c->line, what);
  if (v < 0) {
    if (c->at >= c->n)
      return karst_set_error(ctx, KARST_EPARSE, "%s:%d: PGM header: the file ends before the %s",
                             path, c->line, what);
    return karst_set_error(ctx, KARST_EPARSE,
                           "%s:%d: PGM header: expected the %s (a whole number), got '%c'", path,
                           c->line, what, c->b[c->at]);
  }
  *out = v;
  return KARST_SUCCESS;
}

static karst_error_t read_pgm(karst_ctx_t *ctx, const char *path, const unsigned char *b, size_t n,
                              karst_image_t *out) {
  cursor_t c = {b, n, 2, 1};
  int binary = b[1] == '5';
  long long w, h, maxval;
  karst_error_t err;
  if ((err = pgm_field(ctx, path, &c, "width", &w)) ||
      (err = pgm_field(ctx, path, &c, "height", &h)) ||
      (err = pgm_field(ctx, path, &c, "maxval", &maxval)))
    return err;
  if (maxval < 1 || maxval > 65535)
    return karst_set_error(ctx, KARST_EPARSE,
                           "%s:%d: PGM header: maxval must be 1..65535, got %lld", path, c.line,
                           maxval);
  if ((err = check_size(ctx, path, w, h))) return err;
  size_t np = (size_t)w * (size_t)h;
  float *v = malloc(np * sizeof *v);
  if (!v) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for %zu pixels", path, np);
  if (binary) {
    /* exactly one whitespace byte ends the header */
    if (c.at >= n || !(b[c.at] == ' ' || b[c.at] == '\t' || b[c.at] == '\n' || b[c.at] == '\r')) {
      free(v);
      return karst_set_error(ctx, KARST_EPARSE,
                             "%s:%d: PGM header: expected one whitespace byte after maxval", path,
                             c.line);
    }
    c.at++;
    size_t bps = maxval < 256 ? 1 : 2;
    if (n - c.at < np * bps) {
      free(v);
      return karst_set_error(ctx, KARST_EPARSE,
                             "%s: byte %zu: the pixels are truncated: %zu bytes for %lld x %lld "
                             "pixels of %zu byte(s), expected %zu",
                             path, c.at, n - c.at, w, h, bps, np * bps);
    }
    for (size_t i = 0; i < np; i++) {
      const unsigned char *q = b + c.at + bps * i;
      long long s = bps == 1 ? q[0] : (q[0] << 8 | q[1]);
      if (s > maxval) {
        free(v);
        return karst_set_error(ctx, KARST_EPARSE,
                               "%s: byte %zu: pixel value %lld exceeds maxval %lld", path,
                               c.at + bps * i, s, maxval);
      }
      v[i] = (float)((double)s / (double)maxval);
    }
  } else {
    for (size_t i = 0; i < np; i++) {
      long long s;
      skip_space(&c);
      if (c.at >= n) {
        free(v);
        return karst_set_error(ctx, KARST_EPARSE,
                               "%s:%d: the file ends after %zu of %zu pixel values", path, c.line,
                               i, np);
      }
      s = read_uint(&c);
      if (s < 0 || s > maxval) {
        int line = c.line;
        free(v);
        if (s == -1)
          return karst_set_error(ctx, KARST_EPARSE, "%s:%d: pixel %zu: expected a whole number",
                                 path, line, i);
        return karst_set_error(ctx, KARST_EPARSE, "%s:%d: pixel %zu: value exceeds maxval %lld",
                               path, line, i, maxval);
      }
      v[i] = (float)((double)s / (double)maxval);
    }
  }
  karst_image_destroy(out);
  out->width = (int)w;
  out->height = (int)h;
  out->v = v;
  return KARST_SUCCESS;
}

/* ---------------------------------------------------------------------- */
/* PNG                                                                     */
/* ---------------------------------------------------------------------- */

typedef struct {
  jmp_buf jmp;
  char msg[256];
} png_err_t;

static void png_fail(png_structp png, png_const_charp msg) {
  png_err_t *e = png_get_error_ptr(png);
  snprintf(e->msg, sizeof e->msg, "%s", msg ? msg : "unknown libpng error");
  longjmp(e->jmp, 1);
}

static void png_warn(png_structp png, png_const_charp msg) {
  (void)png;
  (void)msg; /* warnings (e.g. unknown chunks) do not stop the read */
}

/* Everything the PNG decoder touches after setjmp lives here (on the heap),
 * so that nothing is clobbered by a longjmp out of libpng. */
typedef struct {
  png_err_t e;
  png_structp png;
  png_infop info;
  unsigned char *rows;
  png_bytep *rowp;
  float *v;
  png_uint_32 w, h;
  int ch, bits;
  size_t rb;
  karst_error_t err; /* set by the checks between the libpng calls */
} png_state_t;

/* Steps of the decoding that may longjmp: 0 when done, 1 after a libpng
 * error (message in st->e.msg), 2 after a check failed (st->err). */
static int png_decode(karst_ctx_t *ctx, const char *path, FILE *fp, png_state_t *st) {
  if (setjmp(st->e.jmp)) return 1;
  png_set_user_limits(st->png, 1u << 24, 1u << 24);
  png_init_io(st->png, fp);
  png_read_info(st->png, st->info);
  st->w = png_get_image_width(st->png, st->info);
  st->h = png_get_image_height(st->png, st->info);
  if ((st->err = check_size(ctx, path, (long long)st->w, (long long)st->h))) return 2;
  int depth = png_get_bit_depth(st->png, st->info), type = png_get_color_type(st->png, st->info);
  if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(st->png);
  if (type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(st->png);
  if (type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(st->png);
  png_set_interlace_handling(st->png);
  png_read_update_info(st->png, st->info);
  st->ch = png_get_channels(st->png, st->info);
  st->bits = png_get_bit_depth(st->png, st->info);
  st->rb = png_get_rowbytes(st->png, st->info);
  if (!(st->ch == 1 || st->ch == 3) || !(st->bits == 8 || st->bits == 16) ||
      st->rb < (size_t)st->w * (size_t)st->ch * (size_t)(st->bits / 8)) {
    st->err =
        karst_set_error(ctx, KARST_EPARSE,
                        "%s: PNG decodes to %d channel(s) of %d bits, expected grey or RGB of "
                        "8 or 16 bits",
                        path, st->ch, st->bits);
    return 2;
  }
  st->rows = malloc(st->rb * st->h);
  st->rowp = malloc(st->h * sizeof *st->rowp);
  st->v = malloc((size_t)st->w * st->h * sizeof *st->v);
  if (!st->rows || !st->rowp || !st->v) {
    st->err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for %u x %u pixels", path,
                              (unsigned)st->w, (unsigned)st->h);
    return 2;
  }
  for (png_uint_32 y = 0; y < st->h; y++)
    st->rowp[y] = st->rows + st->rb * y;
  png_read_image(st->png, st->rowp);
  png_read_end(st->png, NULL);
  return 0;
}

static karst_error_t read_png(karst_ctx_t *ctx, const char *path, FILE *fp, karst_image_t *out) {
  png_state_t *st = calloc(1, sizeof *st);
  if (!st) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for the PNG reader", path);
  karst_error_t err = KARST_SUCCESS;
  st->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &st->e, png_fail, png_warn);
  if (st->png) st->info = png_create_info_struct(st->png);
  if (!st->png || !st->info) {
    err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for the PNG reader", path);
    goto cleanup;
  }
  int r = png_decode(ctx, path, fp, st);
  if (r == 1) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s: not a readable PNG image: %s", path, st->e.msg);
    goto cleanup;
  }
  if (r == 2) {
    err = st->err;
    goto cleanup;
  }
  double top = st->bits == 16 ? 65535.0 : 255.0;
  size_t bytes = (size_t)(st->bits / 8);
  for (png_uint_32 y = 0; y < st->h; y++) {
    const unsigned char *row = st->rowp[y];
    for (png_uint_32 x = 0; x < st->w; x++) {
      double s[3];
      for (int k = 0; k < st->ch; k++) {
        const unsigned char *q = row + ((size_t)x * (size_t)st->ch + (size_t)k) * bytes;
        s[k] = bytes == 2 ? (double)(q[0] << 8 | q[1]) : (double)q[0];
      }
      double g = st->ch == 1 ? s[0] : LUMA_R * s[0] + LUMA_G * s[1] + LUMA_B * s[2];
      st->v[(size_t)y * st->w + x] = (float)(g / top);
    }
  }
  karst_image_destroy(out);
  out->width = (int)st->w;
  out->height = (int)st->h;
  out->v = st->v;
  st->v = NULL;
cleanup:
  if (st->png) png_destroy_read_struct(&st->png, st->info ? &st->info : NULL, NULL);
  free(st->rows);
  free(st->rowp);
  free(st->v);
  free(st);
  return err;
}

/**
 * Read a PGM or PNG greyscale image (see image.h). Only regular files of at
 * most KARST_IMAGE_MAX_BYTES are opened; the format is told by the magic
 * bytes, not the extension.
 * Time complexity: O(pixels).
 */
karst_error_t karst_image_read(karst_ctx_t *ctx, const char *path, karst_image_t *img) {
  if (!path || !img) return karst_set_error(ctx, KARST_EINVAL, "image: no path or image given");
  FILE *fp = NULL;
  karst_error_t err = karst_i_open_regular(ctx, path, "image", KARST_IMAGE_MAX_BYTES, &fp);
  if (err) return err;
  unsigned char magic[8];
  size_t got = fread(magic, 1, sizeof magic, fp);
  if (got >= 8 && png_sig_cmp(magic, 0, 8) == 0) {
    rewind(fp);
    err = read_png(ctx, path, fp, img);
    fclose(fp);
    return err;
  }
  if (got < 2 || magic[0] != 'P' || (magic[1] != '2' && magic[1] != '5')) {
    fclose(fp);
    return karst_set_error(ctx, KARST_EPARSE,
                           "%s: not a PGM (starting \"P2\" or \"P5\") or PNG image", path);
  }
  /* PGM: the whole file in memory (at most KARST_IMAGE_MAX_BYTES) */
  if (fseek(fp, 0, SEEK_END) != 0) {
    fclose(fp);
    return karst_set_error(ctx, KARST_EIO, "%s: cannot seek", path);
  }
  long size = ftell(fp);
  rewind(fp);
  unsigned char *buf = size > 0 ? malloc((size_t)size) : NULL;
  if (!buf) {
    fclose(fp);
    return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for %ld bytes", path, size);
  }
  size_t n = fread(buf, 1, (size_t)size, fp);
  fclose(fp);
  err = read_pgm(ctx, path, buf, n, img);
  free(buf);
  return err;
}
