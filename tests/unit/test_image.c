/* Greyscale relief images (src/io/image.c): PGM P2/P5 and PNG of every colour
 * type read back to the values written (by hand, or by libpng here), and
 * hostile files refused with a message naming the file and what is wrong,
 * before any large allocation. */
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "karst.h"
#include "test_util.h"

static char dir[] = "/tmp/karst_image_XXXXXX";

static const char *file_with(const char *name, const void *bytes, size_t n) {
  static char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(bytes, 1, n, f), n);
  fclose(f);
  return path;
}

static karst_error_t read_bytes(karst_ctx_t *ctx, const char *name, const void *bytes, size_t n,
                                karst_image_t *img) {
  return karst_image_read(ctx, file_with(name, bytes, n), img);
}

/* P5 8-bit and P2 16-bit with comments: the values by hand (sample / maxval). */
static void test_pgm(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_image_t img;
  karst_image_init(&img);
  const unsigned char p5[] = "P5 3 2 200\n\x00\x64\xc8\x32\x96\x0a";
  assert_int_equal(read_bytes(&ctx, "a.pgm", p5, sizeof p5 - 1, &img), KARST_SUCCESS);
  assert_int_equal(img.width, 3);
  assert_int_equal(img.height, 2);
  const double want5[6] = {0, 0.5, 1, 0.25, 0.75, 0.05};
  for (int i = 0; i < 6; i++)
    assert_close(img.v[i], want5[i], 1e-7);
  const char p2[] = "P2\n# a comment\n2 2 # another\n65535\n0 65535\n 13107\t52428\n";
  assert_int_equal(read_bytes(&ctx, "b.pgm", p2, strlen(p2), &img), KARST_SUCCESS);
  const double want2[4] = {0, 1, 0.2, 0.8};
  for (int i = 0; i < 4; i++)
    assert_close(img.v[i], want2[i], 1e-7);
  /* 16-bit binary: big-endian samples */
  const unsigned char p516[] = "P5\n2 1\n1000\n\x01\xf4\x03\xe8";
  assert_int_equal(read_bytes(&ctx, "c.pgm", p516, sizeof p516 - 1, &img), KARST_SUCCESS);
  assert_close(img.v[0], 0.5, 1e-7);
  assert_close(img.v[1], 1.0, 1e-7);
  karst_image_destroy(&img);
}

/* Write a PNG with libpng: @p rows of @p w x @p h samples (16-bit values
 * stored big-endian as PNG wants), of the given colour type and depth. */
static const char *write_png(const char *name, int w, int h, int type, int depth,
                             const unsigned char *data, size_t rowbytes, const png_color *palette,
                             int npal) {
  static char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  png_infop info = png_create_info_struct(png);
  assert_non_null(png);
  assert_non_null(info);
  if (setjmp(png_jmpbuf(png))) fail();
  png_init_io(png, f);
  png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, depth, type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (palette) png_set_PLTE(png, info, palette, npal);
  png_write_info(png, info);
  for (int y = 0; y < h; y++)
    png_write_row(png, data + (size_t)y * rowbytes);
  png_write_end(png, NULL);
  png_destroy_write_struct(&png, &info);
  fclose(f);
  return path;
}

/* Every PNG colour type: grey 8 and 16 bits, grey 1 bit, grey + alpha (alpha
 * ignored), RGB (Rec. 709 luma), palette (luma of the entries). */
static void test_png(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_image_t img;
  karst_image_init(&img);
  const unsigned char g8[] = {0, 51, 255, 102, 204, 153};
  assert_int_equal(
      karst_image_read(&ctx, write_png("g8.png", 3, 2, PNG_COLOR_TYPE_GRAY, 8, g8, 3, NULL, 0),
                       &img),
      KARST_SUCCESS);
  assert_int_equal(img.width, 3);
  assert_int_equal(img.height, 2);
  for (int i = 0; i < 6; i++)
    assert_close(img.v[i], g8[i] / 255.0, 1e-7);
  const unsigned char g16[] = {0x80, 0x00, 0xff, 0xff}; /* 32768, 65535 */
  assert_int_equal(
      karst_image_read(&ctx, write_png("g16.png", 2, 1, PNG_COLOR_TYPE_GRAY, 16, g16, 4, NULL, 0),
                       &img),
      KARST_SUCCESS);
  assert_close(img.v[0], 32768 / 65535.0, 1e-7);
  assert_close(img.v[1], 1.0, 1e-7);
  const unsigned char g1[] = {0xa0}; /* 1 0 1 0 */
  assert_int_equal(
      karst_image_read(&ctx, write_png("g1.png", 4, 1, PNG_COLOR_TYPE_GRAY, 1, g1, 1, NULL, 0),
                       &img),
      KARST_SUCCESS);
  const double w1[4] = {1, 0, 1, 0};
  for (int i = 0; i < 4; i++)
    assert_close(img.v[i], w1[i], 1e-7);
  const unsigned char ga[] = {100, 7, 200, 250};
  assert_int_equal(
      karst_image_read(
          &ctx, write_png("ga.png", 2, 1, PNG_COLOR_TYPE_GRAY_ALPHA, 8, ga, 4, NULL, 0), &img),
      KARST_SUCCESS);
  assert_close(img.v[0], 100 / 255.0, 1e-7);
  assert_close(img.v[1], 200 / 255.0, 1e-7);
  const unsigned char rgb[] = {255, 0, 0, 0, 255, 0, 10, 20, 30};
  assert_int_equal(
      karst_image_read(&ctx, write_png("rgb.png", 3, 1, PNG_COLOR_TYPE_RGB, 8, rgb, 9, NULL, 0),
                       &img),
      KARST_SUCCESS);
  assert_close(img.v[0], 0.2126, 1e-6);
  assert_close(img.v[1], 0.7152, 1e-6);
  assert_close(img.v[2], (0.2126 * 10 + 0.7152 * 20 + 0.0722 * 30) / 255.0, 1e-6);
  const png_color pal[2] = {{0, 0, 255}, {255, 255, 255}};
  const unsigned char pi[] = {1, 0};
  assert_int_equal(
      karst_image_read(&ctx, write_png("pal.png", 2, 1, PNG_COLOR_TYPE_PALETTE, 8, pi, 2, pal, 2),
                       &img),
      KARST_SUCCESS);
  assert_close(img.v[0], 1.0, 1e-6);
  assert_close(img.v[1], 0.0722, 1e-6);
  karst_image_destroy(&img);
}

/* Hostile files: each refused with its own message naming the file; the
 * image passed in is left unchanged. */
static void test_hostile(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_image_t img;
  karst_image_init(&img);
  const unsigned char ok[] = "P5 1 1 255\n\x80";
  assert_int_equal(read_bytes(&ctx, "ok.pgm", ok, sizeof ok - 1, &img), KARST_SUCCESS);
  struct {
    const char *name, *bytes;
    size_t n;
    karst_error_t code;
    const char *msg;
  } cases[] = {
      {"empty.pgm", "", 0, KARST_EPARSE, "not a PGM"},
      {"magic.pgm", "P6 1 1 255\n\x01\x02\x03", 14, KARST_EPARSE, "not a PGM"},
      {"short.pgm", "P5", 2, KARST_EPARSE, "ends before the width"},
      {"zero.pgm", "P5 0 4 255\n", 11, KARST_EPARSE, "0 x 4 pixels"},
      {"letters.pgm", "P5 x 4 255\n", 11, KARST_EPARSE, "got 'x'"},
      {"digits.pgm", "P5 12345678901 4 255\n", 21, KARST_EPARSE, "more than 9 digits"},
      {"huge.pgm", "P5 100000 100000 255\n", 21, KARST_ERANGE, "exceeds the limit"},
      {"maxval0.pgm", "P5 2 2 0\n", 9, KARST_EPARSE, "maxval must be 1..65535, got 0"},
      {"maxval.pgm", "P2 2 2 70000\n", 13, KARST_EPARSE, "got 70000"},
      {"trunc.pgm", "P5 4 4 255\n\x01\x02", 13, KARST_EPARSE, "byte 11: the pixels are truncated"},
      {"trunc2.pgm", "P2 2 2 9\n1 2\n3", 14, KARST_EPARSE, ":3: the file ends after 3 of 4"},
      {"over.pgm", "P2 2 1 9\n1 12\n", 14, KARST_EPARSE, ":2: pixel 1: value exceeds maxval 9"},
      {"nan.pgm", "P2 2 1 9\n1 z\n", 13, KARST_EPARSE, ":2: pixel 1: expected a whole number"},
      {"over5.pgm", "P5 1 1 100\n\xc8", 12, KARST_EPARSE, "byte 11: pixel value 200 exceeds"},
      {"glued.pgm", "P5 1 1 255\x80", 11, KARST_EPARSE, "one whitespace byte"},
      {"png.png", "\x89PNG\r\n\x1a\n\x00\x00", 10, KARST_EPARSE, "not a readable PNG"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    karst_error_t got = read_bytes(&ctx, cases[i].name, cases[i].bytes, cases[i].n, &img);
    const char *want = cases[i].msg;
    if (got != cases[i].code || !strstr(ctx.errmsg, want) || !strstr(ctx.errmsg, cases[i].name)) {
      print_error("%s: got %s \"%s\", expected %s with \"%s\"\n", cases[i].name,
                  karst_error_name(got), ctx.errmsg, karst_error_name(cases[i].code), want);
      fail();
    }
    /* unchanged */
    assert_int_equal(img.width, 1);
    assert_close(img.v[0], 128 / 255.0, 1e-7);
  }
  /* not a regular file, missing file */
  assert_int_equal(karst_image_read(&ctx, dir, &img), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "directory"));
  assert_int_equal(karst_image_read(&ctx, "/dev/zero", &img), KARST_EIO);
  assert_int_equal(karst_image_read(&ctx, "/nonexistent/r.png", &img), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "/nonexistent/r.png"));

  /* a valid PNG cut in its image data, and one with a damaged CRC */
  unsigned char g8[64 * 64];
  for (int i = 0; i < 64 * 64; i++)
    g8[i] = (unsigned char)(i * 37 % 251);
  const char *p = write_png("full.png", 64, 64, PNG_COLOR_TYPE_GRAY, 8, g8, 64, NULL, 0);
  FILE *f = fopen(p, "rb");
  assert_non_null(f);
  unsigned char buf[8192];
  size_t n = fread(buf, 1, sizeof buf, f);
  fclose(f);
  assert_true(n > 200 && n < sizeof buf);
  assert_int_equal(read_bytes(&ctx, "cut.png", buf, n / 2, &img), KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, "cut.png: not a readable PNG image"));
  buf[n / 2] ^= 0x55;
  assert_int_equal(read_bytes(&ctx, "crc.png", buf, n, &img), KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, "crc.png"));
  assert_int_equal(img.width, 1);

  /* 70000 x 1000 pixels (a tiny 1-bit file) exceed 2^26 pixels: refused before allocating */
  size_t rb = (70000 + 7) / 8;
  unsigned char *zero = calloc(rb, 1000);
  assert_non_null(zero);
  p = write_png("big.png", 70000, 1000, PNG_COLOR_TYPE_GRAY, 1, zero, rb, NULL, 0);
  free(zero);
  assert_int_equal(karst_image_read(&ctx, p, &img), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "70000 x 1000 pixels exceeds the limit"));
  karst_image_destroy(&img);
}

static int setup(void **state) {
  (void)state;
  return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  return test_util_remove_dir(dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pgm),
      cmocka_unit_test(test_png),
      cmocka_unit_test(test_hostile),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
