/* Helpers shared by the unit tests (cmocka 1.1.5 has no floating-point asserts). */
#ifndef KARST_TEST_UTIL_H
#define KARST_TEST_UTIL_H
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* |a - b| <= tol, printing both values on failure. */
#define assert_close(a, b, tol)                                                                    \
  do {                                                                                             \
    double a_ = (a), b_ = (b), t_ = (tol);                                                         \
    if (!(fabs(a_ - b_) <= t_)) {                                                                  \
      print_error("%s = %.17g, expected %s = %.17g (tolerance %g)\n", #a, a_, #b, b_, t_);         \
      fail();                                                                                      \
    }                                                                                              \
  } while (0)

/* Relative agreement: |a - b| <= rel * max(|a|, |b|) (exact when both are 0). */
#define assert_rel(a, b, rel)                                                                      \
  do {                                                                                             \
    double a_ = (a), b_ = (b), r_ = (rel);                                                         \
    double m_ = fmax(fabs(a_), fabs(b_));                                                          \
    if (!(fabs(a_ - b_) <= r_ * m_)) {                                                             \
      print_error("%s = %.17g, expected %s = %.17g (relative tolerance %g)\n", #a, a_, #b, b_,     \
                  r_);                                                                             \
      fail();                                                                                      \
    }                                                                                              \
  } while (0)
/* The whole file @p path, NUL-terminated (caller frees), or NULL when it cannot be read. */
static inline char *test_util_read_file(const char *path) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return NULL;
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *s = n >= 0 ? malloc((size_t)n + 1) : NULL;
  size_t got = s ? fread(s, 1, (size_t)n, fp) : 0;
  if (s) s[got] = '\0';
  fclose(fp);
  return s;
}
/* Remove @p dir and everything in it (a test's scratch directory); 0 on success. */
static inline int test_util_remove_dir(const char *dir) {
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  return system(cmd) == 0 ? 0 : -1;
}
#endif
