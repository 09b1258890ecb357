/* JSON text output shared by run.json, ensemble.json, `karst metrics --format json` and
 * `karst compare --format json`. */
#include "karst/io.h"

/**
 * Write @p s as a JSON string literal (RFC 8259 §7): quotes, backslashes and
 * control characters escaped, other bytes (UTF-8 included) as they are; NULL
 * is written as null. O(length).
 */
void karst_json_string(FILE *fp, const char *s) {
  if (!s) {
    fputs("null", fp);
    return;
  }
  fputc('"', fp);
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    if (*p == '"' || *p == '\\')
      fprintf(fp, "\\%c", *p);
    else if (*p == '\n')
      fputs("\\n", fp);
    else if (*p < 0x20)
      fprintf(fp, "\\u%04x", *p);
    else
      fputc(*p, fp);
  }
  fputc('"', fp);
}
