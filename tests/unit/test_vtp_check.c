/*
 * The .vtp pre-check (src/io/vtp_check.c) through karst_vtk_read_network:
 * hand-made malformed files of each class that crashed, hung or exhausted
 * memory in VTK's XML reader (issue 18) end in KARST_EPARSE / KARST_ERANGE
 * with a message naming the file and the element; the same files with the
 * defect removed, and files karst itself writes, still load.
 *
 * The base64 strings below were made with Python's base64, struct and zlib
 * modules (independently of the code under test): 3 Float32 points
 * (0,0,0) (1,2,3) (2,4,6) = 36 bytes; zlib-compressed to 25 bytes; headers
 * UInt64 [nblocks, blocksize, lastblocksize, compressed sizes...] or, for
 * uncompressed data, UInt32 [byte count].
 */
#include <math.h>
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

#define assert_msg(ctx, sub)                                                                       \
  do {                                                                                             \
    if (!strstr((ctx)->errmsg, (sub))) {                                                           \
      print_error("message \"%s\" lacks \"%s\"\n", (ctx)->errmsg, (sub));                          \
      fail();                                                                                      \
    }                                                                                              \
  } while (0)

/* zlib, UInt64 header [1, 32768, 36, 25]: the three points. */
#define Z_GOOD "AQAAAAAAAAAAgAAAAAAAACQAAAAAAAAAGQAAAAAAAAA=eJxjYEAGDfZAwgGIHCB0AxAfcAAAI48DgA=="
/* The same header claiming 2^28 blocks. */
#define Z_BLOCKS "AAAAEAAAAAAAgAAAAAAAACQAAAAAAAAAGQAAAAAAAAA=eJxjYEAGDfZAwgGIHCB0AxAfcAAAI48DgA=="
/* One flipped bit in byte 5 of the block size: 2^44 + 32768 bytes (16 TiB). */
#define Z_FLIP "AQAAAAAAAAAAgAAAABAAACQAAAAAAAAAGQAAAAAAAAA=eJxjYEAGDfZAwgGIHCB0AxAfcAAAI48DgA=="
/* The compressed data cut after 9 of its 25 bytes. */
#define Z_TRUNC "AQAAAAAAAAAAgAAAAAAAACQAAAAAAAAAGQAAAAAAAAA=eJxjYEAGDfZA"
/* Uncompressed, UInt32 header 36 ... */
#define U_GOOD "JAAAAAAAAAAAAAAAAAAAAAAAgD8AAABAAABAQAAAAEAAAIBAAADAQA=="
/* ... and with its high byte flipped: 16777252 bytes claimed. */
#define U_FLIP "JAAAAQAAAAAAAAAAAAAAAAAAgD8AAABAAABAQAAAAEAAAIBAAADAQA=="

static char dir[64];

/* Write a file of one piece: 3 points in @p points_xml, one polyline 0 1 2. */
static const char *write_file(const char *name, const char *root_attrs, const char *piece_attrs,
                              const char *points_xml, const char *lines_xml) {
  static char path[256];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fprintf(f,
          "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" "
          "byte_order=\"LittleEndian\" %s>\n  <PolyData>\n    <Piece %s>\n"
          "      <Points>\n%s\n      </Points>\n%s\n    </Piece>\n  </PolyData>\n</VTKFile>\n",
          root_attrs, piece_attrs, points_xml, lines_xml);
  fclose(f);
  return path;
}

#define PIECE "NumberOfPoints=\"3\" NumberOfLines=\"1\""
#define LINES                                                                                      \
  "      <Lines>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 "   \
  "2</DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" "                             \
  "format=\"ascii\">3</DataArray>\n      </Lines>"
#define ZLIB64 "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\""
#define BIN_POINTS(data)                                                                           \
  "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" "                  \
  "format=\"binary\">" data "</DataArray>"
#define ASCII_POINTS(data)                                                                         \
  "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" "                  \
  "format=\"ascii\">" data "</DataArray>"

/* Reading @p path must fail with @p code and a message holding the path and each of @p subs. */
static void expect_error(const char *path, karst_error_t code, const char *sub1, const char *sub2) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t n;
  karst_network_init(&n);
  karst_error_t err = karst_vtk_read_network(&ctx, path, &n);
  if (err != code) print_error("%s: got %s: %s\n", path, karst_error_name(err), ctx.errmsg);
  assert_int_equal(err, code);
  assert_msg(&ctx, path);
  if (sub1) assert_msg(&ctx, sub1);
  if (sub2) assert_msg(&ctx, sub2);
  assert_int_equal(n.n_nodes, 0);
  karst_network_destroy(&n);
}

/* Reading @p path must succeed with the three points and two edges of the polyline. */
static void expect_loads(const char *path) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t n;
  karst_network_init(&n);
  karst_error_t err = karst_vtk_read_network(&ctx, path, &n);
  if (err) print_error("%s: %s\n", path, ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  assert_int_equal(n.n_nodes, 3);
  assert_int_equal(n.n_edges, 2);
  assert_true(n.xyz[8] == 6.0); /* the third point, (2, 4, 6) */
  karst_network_destroy(&n);
}

static int setup(void **state) {
  (void)state;
  strcpy(dir, "/tmp/karst_test_vtp_check_XXXXXX");
  return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  return system(cmd) == 0 ? 0 : -1;
}

/* The well-formed variants of every malformed file below load. */
static void test_good_files(void **state) {
  (void)state;
  expect_loads(write_file("z.vtp", ZLIB64, PIECE, BIN_POINTS(Z_GOOD), LINES));
  expect_loads(write_file("u.vtp", "header_type=\"UInt32\"", PIECE, BIN_POINTS(U_GOOD), LINES));
  expect_loads(write_file("a.vtp", "", PIECE, ASCII_POINTS("0 0 0 1 2 3 2 4 6"), LINES));
  /* A file karst writes, read back (zlib, UInt64, inline binary, string arrays). */
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_network_t n, m;
  karst_network_init(&n);
  karst_network_init(&m);
  for (int i = 0; i < 3; i++)
    assert_int_equal(karst_network_add_node(&n, i, 2.0 * i, 3.0 * i, NULL), KARST_SUCCESS);
  assert_int_equal(karst_network_add_edge(&n, 0, 1, NULL), KARST_SUCCESS);
  assert_int_equal(karst_network_add_edge(&n, 1, 2, NULL), KARST_SUCCESS);
  assert_int_equal(karst_network_set_label(&n, 1, "B"), KARST_SUCCESS);
  char path[256];
  snprintf(path, sizeof path, "%s/own.vtp", dir);
  assert_int_equal(karst_vtk_write_network(&ctx, path, &n), KARST_SUCCESS);
  assert_int_equal(karst_vtk_read_network(&ctx, path, &m), KARST_SUCCESS);
  assert_int_equal(m.n_nodes, 3);
  assert_int_equal(m.n_edges, 2);
  karst_network_destroy(&n);
  karst_network_destroy(&m);
}

/* Structures VTK dereferenced NULL on: no Piece, cells without their arrays. */
static void test_missing_elements(void **state) {
  (void)state;
  char path[256];
  snprintf(path, sizeof path, "%s/nopiece.vtp", dir);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs("<VTKFile type=\"PolyData\" version=\"1.0\"><PolyData></PolyData></VTKFile>\n", f);
  fclose(f);
  expect_error(path, KARST_EPARSE, "<PolyData> at byte", "holds no <Piece>");
  expect_error(write_file("nooffsets.vtp", "", PIECE, ASCII_POINTS("0 0 0 1 2 3 2 4 6"),
                          "      <Lines>\n        <DataArray type=\"Int64\" Name=\"connectivity\" "
                          "format=\"ascii\">0 1 2</DataArray>\n      </Lines>"),
               KARST_EPARSE, "<Lines>", "no DataArray named \"offsets\"");
  expect_error(write_file("nolines.vtp", "", PIECE, ASCII_POINTS("0 0 0 1 2 3 2 4 6"), ""),
               KARST_EPARSE, "<Piece>", "NumberOfLines is 1 but the piece has no <Lines>");
  expect_error(write_file("nopoints.vtp", "", PIECE, "", LINES), KARST_EPARSE, "<Points>",
               "no DataArray for the 3 points");
  /* The last offset sizes VTK's connectivity array: 10^11 would be 800 GB. */
  expect_error(write_file("bigoffset.vtp", "", PIECE, ASCII_POINTS("0 0 0 1 2 3 2 4 6"),
                          "      <Lines>\n        <DataArray type=\"Int64\" Name=\"connectivity\" "
                          "format=\"ascii\">0 1 2</DataArray>\n        <DataArray type=\"Int64\" "
                          "Name=\"offsets\" format=\"ascii\">100000000000</DataArray>\n      "
                          "</Lines>"),
               KARST_EPARSE, "<DataArray Name=\"offsets\">",
               "the last offset is 100000000000; the connectivity holds 3 values");
  /* Arrays of the wrong kind where VTK expects numbers. */
  expect_error(write_file("strpoints.vtp", "", PIECE,
                          "        <DataArray type=\"String\" Name=\"Points\" "
                          "NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 2 3 2 4 6</DataArray>",
                          LINES),
               KARST_EPARSE, "<DataArray Name=\"Points\">", "points must be numbers, not String");
  expect_error(
      write_file("fconn.vtp", "", PIECE, ASCII_POINTS("0 0 0 1 2 3 2 4 6"),
                 "      <Lines>\n        <DataArray type=\"Float32\" Name=\"connectivity\" "
                 "format=\"ascii\">0 1 2</DataArray>\n        <DataArray type=\"Int64\" "
                 "Name=\"offsets\" format=\"ascii\">3</DataArray>\n      </Lines>"),
      KARST_EPARSE, "<DataArray Name=\"connectivity\">", "connectivity must be integers");
  /* Unclosed element (a file cut short). */
  snprintf(path, sizeof path, "%s/cut.vtp", dir);
  f = fopen(path, "w");
  assert_non_null(f);
  fputs("<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"0\">", f);
  fclose(f);
  expect_error(path, KARST_EPARSE, "<Piece> at byte", "not closed before the end of the file");
}

/* Counts beyond what the file could hold. */
static void test_counts(void **state) {
  (void)state;
  /* VTK spent minutes in CreateArray on this. */
  expect_error(write_file("ncomp.vtp", "", PIECE,
                          "        <DataArray type=\"Float32\" Name=\"Points\" "
                          "NumberOfComponents=\"1000000000\" format=\"ascii\">0 0 0 1 2 3 2 4 "
                          "6</DataArray>",
                          LINES),
               KARST_ERANGE, "<DataArray Name=\"Points\">",
               "NumberOfComponents is 1000000000; it must be 1 to 1024");
  expect_error(write_file("npoints.vtp", "", "NumberOfPoints=\"100\" NumberOfLines=\"1\"",
                          ASCII_POINTS("0 0 0 1 2 3 2 4 6"), LINES),
               KARST_EPARSE, "<DataArray Name=\"Points\">",
               "needs 100 tuples of 3 components; its data holds 9 values");
  /* More points than a file of this size could hold even at zlib's best ratio (1032:1). */
  expect_error(write_file("npoints2.vtp", "", "NumberOfPoints=\"1000000000\" NumberOfLines=\"1\"",
                          ASCII_POINTS("0 0 0 1 2 3 2 4 6"), LINES),
               KARST_ERANGE, "<Piece>", "NumberOfPoints is 1000000000, more than a");
  expect_error(write_file("nlines.vtp", "",
                          "NumberOfPoints=\"3\" NumberOfLines=\"99999999999999999\"",
                          ASCII_POINTS("0 0 0 1 2 3 2 4 6"), LINES),
               KARST_ERANGE, "<Piece>", "NumberOfLines is 99999999999999999, more than a");
}

/* Binary block headers: VTK allocated what they claim before noticing. */
static void test_block_headers(void **state) {
  (void)state;
  expect_error(write_file("blocks.vtp", ZLIB64, PIECE, BIN_POINTS(Z_BLOCKS), LINES), KARST_EPARSE,
               "<DataArray Name=\"Points\">", "declares 268435456 blocks");
  expect_error(write_file("flip.vtp", ZLIB64, PIECE, BIN_POINTS(Z_FLIP), LINES), KARST_EPARSE,
               "<DataArray Name=\"Points\">", "blocks of 17592186077184 bytes");
  expect_error(write_file("trunc.vtp", ZLIB64, PIECE, BIN_POINTS(Z_TRUNC), LINES), KARST_EPARSE,
               "<DataArray Name=\"Points\">", "declares 25 compressed bytes; the file holds 9");
  expect_error(write_file("uflip.vtp", "header_type=\"UInt32\"", PIECE, BIN_POINTS(U_FLIP), LINES),
               KARST_EPARSE, "<DataArray Name=\"Points\">",
               "declares 16777252 bytes; the file holds 36");
  expect_error(write_file("notb64.vtp", ZLIB64, PIECE, BIN_POINTS("AQAA*AAA"), LINES), KARST_EPARSE,
               "<DataArray Name=\"Points\">", "not valid base64");
  expect_error(write_file("foo.vtp", "compressor=\"vtkFooDataCompressor\"", PIECE,
                          BIN_POINTS(Z_GOOD), LINES),
               KARST_EUNSUPPORTED, "<VTKFile>", "compressor \"vtkFooDataCompressor\" is not read");
  /* Appended data claimed but absent. */
  expect_error(write_file("noapp.vtp", ZLIB64, PIECE,
                          "        <DataArray type=\"Float32\" Name=\"Points\" "
                          "NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>",
                          LINES),
               KARST_EPARSE, "<DataArray Name=\"Points\">", "the file has no AppendedData");
}

/* A non-finite ASCII coordinate is refused with the file named. */
static void test_inf(void **state) {
  (void)state;
  expect_error(write_file("inf.vtp", "", PIECE, ASCII_POINTS("0 0 0 1 2 inf 2 4 6"), LINES),
               KARST_EPARSE, "<DataArray Name=\"Points\">",
               "value 5 ('inf') is not a finite number");
  expect_error(write_file("huge.vtp", "", PIECE, ASCII_POINTS("0 0 0 1 2 3 2 4 1e999"), LINES),
               KARST_EPARSE, "<DataArray Name=\"Points\">", "value 8 ('1e999')");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_good_files, setup, teardown),
      cmocka_unit_test_setup_teardown(test_missing_elements, setup, teardown),
      cmocka_unit_test_setup_teardown(test_counts, setup, teardown),
      cmocka_unit_test_setup_teardown(test_block_headers, setup, teardown),
      cmocka_unit_test_setup_teardown(test_inf, setup, teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
