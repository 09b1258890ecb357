/*
 * The JSON reader (include/karst/json.h): a document with every kind of value,
 * escapes decoded to the UTF-8 bytes worked out by hand (RFC 8259 §7, RFC 3629),
 * positions of values, and malformed inputs each rejected with the LINE:COL
 * counted by hand (1-based, columns in bytes) and a message saying what was wrong.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "karst.h"
#include "test_util.h"

static karst_json_t *parse_ok(const char *text) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_json_t *v = NULL;
  karst_error_t err = karst_json_parse(&ctx, "t.json", text, strlen(text), &v);
  if (err) print_error("unexpected error on %s: %s\n", text, ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  assert_non_null(v);
  return v;
}

static void test_document(void **state) {
  (void)state;
  const char *doc =
      "{\n"
      "  \"name\": \"a\\\"b\\\\c\\/\\n\\t\\u00e9\\ud83d\\ude00\",\n"
      "  \"n\": -0.5e2, \"big\": 12345678901234567890, \"zero\": 0,\n"
      "  \"flags\": [true, false, null],\n"
      "  \"nested\": {\"empty_o\": {}, \"empty_a\": [ ], \"list\": [[1], {\"k\": \"v\"}]}\n"
      "}\n";
  karst_json_t *v = parse_ok(doc);
  assert_int_equal(v->type, KARST_JSON_OBJECT);
  assert_int_equal(v->n, 6);
  assert_string_equal(v->keys[0], "name");
  /* a " b \ c / LF TAB é (U+00E9 = C3 A9) 😀 (U+1F600 from the pair D83D DE00 = F0 9F 98 80) */
  assert_string_equal(karst_json_get(v, "name")->text, "a\"b\\c/\n\t\xC3\xA9\xF0\x9F\x98\x80");
  const karst_json_t *n = karst_json_get(v, "n");
  assert_int_equal(n->type, KARST_JSON_NUMBER);
  assert_close(n->number, -50.0, 0.0);
  assert_string_equal(n->text, "-0.5e2"); /* the literal as written */
  assert_int_equal(n->line, 3);
  assert_int_equal(n->col, 8); /* `  "n": -` : the '-' is byte 8 of line 3 */
  assert_string_equal(karst_json_get(v, "big")->text, "12345678901234567890");
  assert_close(karst_json_get(v, "big")->number, 12345678901234567890.0, 0.0);
  const karst_json_t *f = karst_json_get(v, "flags");
  assert_int_equal(f->n, 3);
  assert_int_equal(f->items[0].type, KARST_JSON_TRUE);
  assert_int_equal(f->items[1].type, KARST_JSON_FALSE);
  assert_int_equal(f->items[2].type, KARST_JSON_NULL);
  assert_true(karst_json_is_scalar(&f->items[2]));
  assert_false(karst_json_is_scalar(f));
  const karst_json_t *ne = karst_json_get(v, "nested");
  assert_int_equal(karst_json_get(ne, "empty_o")->type, KARST_JSON_OBJECT);
  assert_int_equal(karst_json_get(ne, "empty_o")->n, 0);
  assert_int_equal(karst_json_get(ne, "empty_a")->type, KARST_JSON_ARRAY);
  assert_int_equal(karst_json_get(ne, "empty_a")->n, 0);
  const karst_json_t *l = karst_json_get(ne, "list");
  assert_int_equal(l->items[0].items[0].number, 1);
  assert_string_equal(karst_json_get(&l->items[1], "k")->text, "v");
  assert_null(karst_json_get(v, "missing"));
  assert_null(karst_json_get(f, "name")); /* not an object */
  karst_json_free(v);

  /* A scalar at the top, a byte order mark, white space around. */
  v = parse_ok("\xEF\xBB\xBF \r\n\t\"x\" \n");
  assert_int_equal(v->type, KARST_JSON_STRING);
  assert_string_equal(v->text, "x");
  assert_int_equal(v->line, 2);
  assert_int_equal(v->col, 2);
  karst_json_free(v);
  v = parse_ok("-0");
  assert_true(v->number == 0 && signbit(v->number));
  karst_json_free(v);
  karst_json_free(NULL);
}

/* Each malformed input, the position (hand-counted) and a fragment of the message. */
static void test_malformed(void **state) {
  (void)state;
  static char deep[600];
  memset(deep, '[', 300);
  deep[300] = '\0';
  const struct {
    const char *text, *where, *what;
  } bad[] = {
      {"", "t.json:1:1: ", "expected a value, got the end of the input"},
      {"   \n  ", "t.json:2:3: ", "expected a value, got the end of the input"},
      {"{\"a\": 1,}", "t.json:1:9: ",
       "expected a member name in double quotes in the object opened at 1:1, got '}'"},
      {"{1: 2}", "t.json:1:2: ", "expected a member name in double quotes"},
      {"[1, 2", "t.json:1:6: ",
       "expected ',' or ']' after element 2 of the array opened at 1:1, got the end of the input"},
      {"[1,,2]", "t.json:1:4: ",
       "expected a value (object, array, string, number, true, false or null), got ','"},
      {"{\"a\" 1}", "t.json:1:6: ", "expected ':' after the member name \"a\", got '1'"},
      {"{\n  \"a\": tru\n}", "t.json:2:8: ",
       "expected a value (object, array, string, number, true, false or null), got 't'"},
      {"{\"a\": 1 \"b\": 2}",
       "t.json:1:9: ", "expected ',' or '}' after member 1 of the object opened at 1:1, got '\"'"},
      {"\"abc", "t.json:1:1: ", "unterminated string"},
      {"[\"a\nb\"]", "t.json:1:4: ", "control character 0x0a in a string"},
      {"\"\\x\"", "t.json:1:2: ", "invalid escape in a string: '\\' followed by 'x'"},
      {"\"\\u12G4\"", "t.json:1:2: ", "\\u must be followed by four hexadecimal digits"},
      {"\"\\ud800x\"",
       "t.json:1:2: ", "\\uD800 is a high surrogate not followed by a low surrogate"},
      {"\"\\udc00\"", "t.json:1:2: ", "\\uDC00 is a low surrogate without a high surrogate"},
      {"\"\\u0000\"", "t.json:1:2: ", "\\u0000 (a NUL character) is not supported"},
      {"\"\xFF\"", "t.json:1:2: ", "invalid UTF-8 (byte 0xff)"},
      {"\"\xC0\x80\"", "t.json:1:2: ", "invalid UTF-8 (byte 0xc0)"},     /* overlong NUL */
      {"\"\xED\xA0\x80\"", "t.json:1:2: ", "invalid UTF-8 (byte 0xed)"}, /* encoded surrogate */
      {"01", "t.json:1:1: ", "a number must not have leading zeros"},
      {"-", "t.json:1:2: ", "expected a digit after '-'"},
      {"[-x]", "t.json:1:3: ", "expected a digit after '-'"},
      {"1.", "t.json:1:3: ", "expected a digit after the decimal point"},
      {"1e+", "t.json:1:4: ", "expected a digit in the exponent"},
      {"1e999", "t.json:1:1: ", "the number 1e999 is beyond the range of a double"},
      {"+1", "t.json:1:1: ", "got '+'"},
      {"{\"a\":1,\n \"a\":2}",
       "t.json:2:2: ", "duplicate member name \"a\" (its first value is at 1:6)"},
      {"[1] 2", "t.json:1:5: ", "unexpected '2' after the end of the JSON value"},
      {"nul", "t.json:1:1: ", "got 'n'"},
      {"truex", "t.json:1:5: ", "unexpected 'x' after the end of the JSON value"},
      {deep, "t.json:1:257: ", "arrays and objects nested deeper than 256"},
  };
  for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    karst_json_t *v = (karst_json_t *)&ctx; /* must be reset to NULL */
    karst_error_t err = karst_json_parse(&ctx, "t.json", bad[k].text, strlen(bad[k].text), &v);
    if (err != KARST_EPARSE || strncmp(ctx.errmsg, bad[k].where, strlen(bad[k].where)) != 0 ||
        !strstr(ctx.errmsg, bad[k].what)) {
      print_error("case %zu (%s): error %d, message \"%s\"; expected \"%s...%s\"\n", k, bad[k].text,
                  (int)err, ctx.errmsg, bad[k].where, bad[k].what);
      fail();
    }
    assert_null(v);
  }
}

static void test_read_file(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_json_t *v = NULL;
  assert_int_equal(karst_json_read_file(&ctx, "/nonexistent/e.json", &v), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "/nonexistent/e.json"));
  char path[] = "/tmp/karst_test_json_XXXXXX";
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  const char *text = "{\"a\": [1, 2],\n \"b\": [3 4]}\n";
  assert_int_equal(write(fd, text, strlen(text)), (ssize_t)strlen(text));
  close(fd);
  assert_int_equal(karst_json_read_file(&ctx, path, &v), KARST_EPARSE);
  char want[128];
  snprintf(want, sizeof want, "%s:2:10: expected ',' or ']' after element 1", path);
  assert_non_null(strstr(ctx.errmsg, want));
  assert_null(v);
  unlink(path);
}

/* The writer (karst_json_string) and the reader agree on every byte string: well-formed UTF-8
 * comes back as it is; a byte outside well-formed UTF-8 (a Latin-1 path "h\xf6hle", an overlong
 * "\xc0\xaf", a surrogate "\xed\xa0\x80", a lone continuation byte) is written as \u00XX and
 * read back as the UTF-8 of U+00XX (hand-encoded: U+00F6 = C3 B6, U+00C0 = C3 80, ...). */
static void test_writer_round_trip(void **state) {
  (void)state;
  static const struct {
    const char *in, *out;
  } cases[] = {
      {"/data/h\xc3\xb6hle/s.yaml", "/data/h\xc3\xb6hle/s.yaml"},
      {"/data/h\xf6hle/s.yaml", "/data/h\xc3\xb6hle/s.yaml"},
      {"a\xc0\xaf", "a\xc3\x80\xc2\xaf"},
      {"\xed\xa0\x80", "\xc3\xad\xc2\xa0\xc2\x80"},
      {"\xf0\x9f\x98\x80 q\"\\\n\x01", "\xf0\x9f\x98\x80 q\"\\\n\x01"},
      {"x\xe2\x82", "x\xc3\xa2\xc2\x82"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char *buf = NULL;
    size_t len = 0;
    FILE *fp = open_memstream(&buf, &len);
    assert_non_null(fp);
    karst_json_string(fp, cases[i].in);
    fclose(fp);
    karst_json_t *v = parse_ok(buf);
    assert_int_equal(v->type, KARST_JSON_STRING);
    assert_string_equal(v->text, cases[i].out);
    karst_json_free(v);
    free(buf);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_document),
      cmocka_unit_test(test_malformed),
      cmocka_unit_test(test_read_file),
      cmocka_unit_test(test_writer_round_trip),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
