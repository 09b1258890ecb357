/*
 * Relative and normalised paths (include/karst/io.h): karst_path_relative on real directories
 * (with "..", "." and a symbolic link), karst_path_normalize by hand.
 */
#include <limits.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "karst.h"

static char root[64];

static int setup(void **state) {
  (void)state;
  snprintf(root, sizeof root, "/tmp/karst_test_path_XXXXXX");
  if (!mkdtemp(root)) return -1;
  char p[256];
  const char *dirs[] = {"a", "a/b", "a/b/c", "d", "ab"};
  for (size_t i = 0; i < sizeof dirs / sizeof dirs[0]; i++) {
    snprintf(p, sizeof p, "%s/%s", root, dirs[i]);
    if (mkdir(p, 0777) != 0) return -1;
  }
  char target[256];
  snprintf(target, sizeof target, "%s/a/b", root);
  snprintf(p, sizeof p, "%s/link", root); /* link -> a/b */
  return symlink(target, p);
}

static int teardown(void **state) {
  (void)state;
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", root);
  return system(cmd);
}

static void expect_rel(const char *from, const char *to, const char *want) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char f[256], t[256], *out = NULL;
  snprintf(f, sizeof f, "%s/%s", root, from);
  snprintf(t, sizeof t, "%s/%s", root, to);
  assert_int_equal(karst_path_relative(&ctx, f, t, &out), KARST_SUCCESS);
  if (strcmp(out, want) != 0)
    fail_msg("from %s to %s: got '%s', expected '%s'", from, to, out, want);
  free(out);
}

/* By hand from the tree: root/{a/{b/c}, d, ab}, link -> a/b. */
static void test_relative(void **state) {
  (void)state;
  expect_rel("a", "a/x.csv", "x.csv");
  expect_rel("a/b/c", "d/x.csv", "../../../d/x.csv");
  expect_rel("d", "a/b/../x.csv", "../a/x.csv"); /* ".." resolved */
  expect_rel("a/./b", "a/b/c/./y", "c/y");       /* "." resolved */
  expect_rel("a", "ab/x", "../ab/x");            /* "a" is not a prefix of "ab" */
  expect_rel("a/b/c", "a/b", "..");              /* a directory above */
  expect_rel("a/b", "a/b", ".");                 /* the same */
  expect_rel("link", "a/b/c/z", "c/z");          /* the link followed */
  expect_rel("d", "x", "../x");
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char *out = NULL;
  assert_int_equal(karst_path_relative(&ctx, "/", "/etc/passwd", &out), KARST_SUCCESS);
  assert_string_equal(out, "etc/passwd");
  free(out);
  char missing[256];
  snprintf(missing, sizeof missing, "%s/nowhere", root);
  assert_int_equal(karst_path_relative(&ctx, missing, "/etc/passwd", &out), KARST_EIO);
  assert_null(out);
  assert_non_null(strstr(ctx.errmsg, "nowhere"));
  assert_int_equal(karst_path_relative(&ctx, root, "/no/such/dir/x", &out), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "/no/such/dir/x"));
}

static void expect_norm(const char *in, const char *want) {
  char *out = karst_path_normalize(in);
  assert_non_null(out);
  if (strcmp(out, want) != 0) fail_msg("'%s': got '%s', expected '%s'", in, out, want);
  free(out);
}

static void test_normalize(void **state) {
  (void)state;
  expect_norm("a/./b/../c//d", "a/c/d");
  expect_norm("build/../datasets/published_metrics.csv", "datasets/published_metrics.csv");
  expect_norm("../x/..", "..");
  expect_norm("../../a", "../../a");
  expect_norm("a/../..", "..");
  expect_norm("/..", "/");
  expect_norm("/a/../../b", "/b");
  expect_norm("./", ".");
  expect_norm("", ".");
  expect_norm("/", "/");
  expect_norm("a/", "a");
  expect_norm("...", "...");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_relative),
      cmocka_unit_test(test_normalize),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
