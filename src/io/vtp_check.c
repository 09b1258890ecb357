/* A check of a VTK XML PolyData (.vtp) file before VTK's reader sees it
 * (io/input_internal.h).
 *
 * VTK's XML reader trusts what the file declares: it allocates
 * NumberOfPoints x NumberOfComponents values before reading them, a
 * connectivity array as long as the last offset says, a block table as long
 * as a compressed header says, and it dereferences NULL on some missing
 * elements. This file reads the subset of VTK XML that karst reads (one
 * VTKFile of type PolyData, its pieces and data arrays, inline or appended
 * data, raw or base64, zlib/LZ4/LZMA compressed or not) and checks every count the
 * reader would act on against the bytes the file holds, so that a malformed
 * file ends in a message naming the file and the element, never in a crash,
 * a hang or a huge allocation.
 *
 * Reference: "VTK File Formats", VTK User's Guide (Kitware), section "XML
 * File Formats"; the binary layouts below were confirmed against files
 * written by VTK 9.1's vtkXMLPolyDataWriter in every data mode.
 */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "io/input_internal.h"
#include "io/vtp_write_internal.h"

/** Largest NumberOfComponents accepted (karst's widest array has a few dozen). */
#define VTP_MAX_COMPONENTS 1024
/** Deepest element nesting accepted (VTK's own files are 6 deep). */
#define VTP_MAX_DEPTH 64
/** Attributes per element read (VTK writes at most 8). */
#define VTP_MAX_ATTRS 32
/** Largest output of one input byte: deflate (zlib) at most 1032:1 (zlib's FAQ), LZ4 at
 * most 255:1 (a 255-byte length extension per input byte). LZMA's range coder, with 11-bit
 * probabilities, spends at least about 0.3 bit on a 273-byte repeated match, about 7300:1;
 * xz reaches 6781:1 on 64 MiB of zeros: 8192 bounds it. */
#define ZLIB_MAX_RATIO 1032
#define LZ4_MAX_RATIO 255
#define LZMA_MAX_RATIO 8192
/** Slack for tiny blocks whose container overhead exceeds their payload. */
#define BLOCK_SLACK 64
/** Block size always accepted (VTK writes 32 KiB blocks). */
#define VTP_BLOCK_SIZE_FLOOR (16ULL << 20)

enum { COMP_NONE = 0, COMP_ZLIB = 1, COMP_LZ4 = 2, COMP_LZMA = 3 };

typedef struct {
  size_t name, name_len, val, val_len;
} vattr_t;

typedef struct {
  size_t at; /* byte offset of '<' */
  size_t name, name_len;
  int parent; /* index, -1 for the root */
  int n_attrs;
  vattr_t attrs[VTP_MAX_ATTRS];
  size_t text, text_len; /* character data right after the start tag */
} velem_t;

typedef struct {
  karst_ctx_t *ctx;
  const char *file;
  const unsigned char *s;
  size_t len;
  velem_t *el;
  int n_el, cap_el;
  /* VTKFile attributes */
  int header64, big_endian, compressor, version_major;
  /* AppendedData */
  int has_app, app_base64;
  size_t app, app_len;
} vc_t;

/* ------------------------------------------------------------------------ */
/* Messages                                                                 */
/* ------------------------------------------------------------------------ */

static int attr(const vc_t *v, const velem_t *e, const char *name, const char **val, size_t *n);

/* "<DataArray Name="x"> at byte N" for messages. */
static void describe(const vc_t *v, const velem_t *e, char *buf, size_t sz) {
  const char *nm;
  size_t nn;
  if (attr(v, e, "Name", &nm, &nn))
    snprintf(buf, sz, "<%.*s Name=\"%.*s\"> at byte %zu", (int)e->name_len,
             (const char *)v->s + e->name, (int)(nn > 64 ? 64 : nn), nm, e->at);
  else
    snprintf(buf, sz, "<%.*s> at byte %zu", (int)e->name_len, (const char *)v->s + e->name, e->at);
}

#define FAIL_EL(v, e, code, ...)                                                                   \
  do {                                                                                             \
    char where_[160], what_[1024];                                                                 \
    describe((v), (e), where_, sizeof where_);                                                     \
    snprintf(what_, sizeof what_, __VA_ARGS__);                                                    \
    return karst_set_error((v)->ctx, (code), "%s: %s: %s", (v)->file, where_, what_);              \
  } while (0)

#define FAIL_AT(v, pos, ...)                                                                       \
  do {                                                                                             \
    char what_[1024];                                                                              \
    snprintf(what_, sizeof what_, __VA_ARGS__);                                                    \
    return karst_set_error((v)->ctx, KARST_EPARSE, "%s: byte %zu: %s", (v)->file, (size_t)(pos),   \
                           what_);                                                                 \
  } while (0)

/* ------------------------------------------------------------------------ */
/* XML: elements, attributes and the character data after each start tag    */
/* ------------------------------------------------------------------------ */

static int is_ws(unsigned char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}
static int is_name_start(unsigned char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_' || c == ':' || c >= 0x80;
}
static int is_name_char(unsigned char c) {
  return is_name_start(c) || (c >= '0' && c <= '9') || c == '-' || c == '.';
}

static const unsigned char *find(const unsigned char *s, size_t from, size_t len, const char *pat) {
  size_t k = strlen(pat);
  for (size_t i = from; i + k <= len; i++)
    if (s[i] == (unsigned char)pat[0] && memcmp(s + i, pat, k) == 0) return s + i;
  return NULL;
}

static int name_is(const vc_t *v, const velem_t *e, const char *name) {
  size_t k = strlen(name);
  return e->name_len == k && memcmp(v->s + e->name, name, k) == 0;
}

static int attr(const vc_t *v, const velem_t *e, const char *name, const char **val, size_t *n) {
  size_t k = strlen(name);
  for (int i = 0; i < e->n_attrs; i++)
    if (e->attrs[i].name_len == k && memcmp(v->s + e->attrs[i].name, name, k) == 0) {
      *val = (const char *)v->s + e->attrs[i].val;
      *n = e->attrs[i].val_len;
      return 1;
    }
  return 0;
}

static int attr_is(const vc_t *v, const velem_t *e, const char *name, const char *want) {
  const char *s;
  size_t n;
  return attr(v, e, name, &s, &n) && n == strlen(want) && memcmp(s, want, n) == 0;
}

/* A non-negative decimal attribute; 0: absent (*out = dflt), 1: read, -1: malformed. */
static int attr_count(const vc_t *v, const velem_t *e, const char *name, uint64_t dflt,
                      uint64_t *out) {
  const char *s;
  size_t n;
  *out = dflt;
  if (!attr(v, e, name, &s, &n)) return 0;
  size_t i = 0;
  while (i < n && is_ws((unsigned char)s[i]))
    i++;
  if (i == n) return -1;
  uint64_t x = 0;
  for (; i < n && s[i] >= '0' && s[i] <= '9'; i++) {
    if (x > (UINT64_MAX - 9) / 10) return -1;
    x = 10 * x + (uint64_t)(s[i] - '0');
  }
  while (i < n && is_ws((unsigned char)s[i]))
    i++;
  if (i != n) return -1;
  *out = x;
  return 1;
}

static karst_error_t push(vc_t *v, size_t at, size_t name, size_t name_len, int parent,
                          int *index) {
  if (v->n_el == v->cap_el) {
    int cap = v->cap_el ? 2 * v->cap_el : 64;
    velem_t *e = realloc(v->el, (size_t)cap * sizeof *e);
    if (!e) return karst_set_error(v->ctx, KARST_ENOMEM, "%s: out of memory", v->file);
    v->el = e;
    v->cap_el = cap;
  }
  velem_t *e = &v->el[v->n_el];
  memset(e, 0, sizeof *e);
  e->at = at;
  e->name = name;
  e->name_len = name_len;
  e->parent = parent;
  *index = v->n_el++;
  return KARST_SUCCESS;
}

static karst_error_t parse_xml(vc_t *v) {
  const unsigned char *s = v->s;
  const size_t len = v->len;
  int stack[VTP_MAX_DEPTH], depth = 0, seen_root = 0, text_of = -1;
  size_t p = 0;
  karst_error_t err;
  if (len >= 3 && s[0] == 0xEF && s[1] == 0xBB && s[2] == 0xBF) p = 3;
  while (p < len) {
    if (s[p] != '<') {
      size_t t = p;
      while (p < len && s[p] != '<')
        p++;
      if (text_of >= 0) {
        v->el[text_of].text = t;
        v->el[text_of].text_len = p - t;
      } else if (depth == 0) {
        for (size_t i = t; i < p; i++)
          if (!is_ws(s[i])) FAIL_AT(v, i, "text outside the VTKFile element");
      }
      text_of = -1;
      continue;
    }
    text_of = -1;
    if (p + 1 < len && s[p + 1] == '?') {
      const unsigned char *e = find(s, p + 2, len, "?>");
      if (!e) FAIL_AT(v, p, "unterminated <? ... ?>");
      p = (size_t)(e - s) + 2;
      continue;
    }
    if (p + 3 < len && memcmp(s + p, "<!--", 4) == 0) {
      const unsigned char *e = find(s, p + 4, len, "-->");
      if (!e) FAIL_AT(v, p, "unterminated comment");
      p = (size_t)(e - s) + 3;
      continue;
    }
    if (p + 8 < len && memcmp(s + p, "<![CDATA[", 9) == 0) {
      const unsigned char *e = find(s, p + 9, len, "]]>");
      if (!e) FAIL_AT(v, p, "unterminated CDATA section");
      if (depth == 0) FAIL_AT(v, p, "CDATA outside the VTKFile element");
      p = (size_t)(e - s) + 3;
      continue;
    }
    if (p + 1 < len && s[p + 1] == '!')
      FAIL_AT(v, p, "a <!DOCTYPE> or <!ENTITY> declaration; VTK files have none");
    if (p + 1 < len && s[p + 1] == '/') { /* end tag */
      size_t n0 = p + 2, n1 = n0;
      while (n1 < len && is_name_char(s[n1]))
        n1++;
      size_t q = n1;
      while (q < len && is_ws(s[q]))
        q++;
      if (q >= len || s[q] != '>') FAIL_AT(v, p, "malformed end tag");
      if (depth == 0) FAIL_AT(v, p, "end tag </%.*s> without a start tag", (int)(n1 - n0), s + n0);
      const velem_t *open = &v->el[stack[depth - 1]];
      if (open->name_len != n1 - n0 || memcmp(s + open->name, s + n0, n1 - n0) != 0)
        FAIL_AT(v, p, "end tag </%.*s> does not close <%.*s> (byte %zu)", (int)(n1 - n0), s + n0,
                (int)open->name_len, s + open->name, open->at);
      depth--;
      p = q + 1;
      continue;
    }
    /* start tag */
    size_t n0 = p + 1, n1 = n0;
    if (n1 >= len || !is_name_start(s[n1])) FAIL_AT(v, p, "'<' not followed by an element name");
    while (n1 < len && is_name_char(s[n1]))
      n1++;
    if (depth == 0 && seen_root) FAIL_AT(v, p, "a second top-level element");
    if (depth == VTP_MAX_DEPTH) FAIL_AT(v, p, "elements nested deeper than %d", VTP_MAX_DEPTH);
    int idx = -1;
    if ((err = push(v, p, n0, n1 - n0, depth ? stack[depth - 1] : -1, &idx))) return err;
    velem_t *e = &v->el[idx];
    size_t q = n1;
    int closed = 0;
    for (;;) {
      size_t w = q;
      while (q < len && is_ws(s[q]))
        q++;
      if (q >= len) FAIL_AT(v, p, "unterminated start tag <%.*s", (int)e->name_len, s + e->name);
      if (s[q] == '>') {
        q++;
        break;
      }
      if (s[q] == '/' && q + 1 < len && s[q + 1] == '>') {
        q += 2;
        closed = 1;
        break;
      }
      if (q == w || !is_name_start(s[q]))
        FAIL_AT(v, q, "malformed attribute in <%.*s>", (int)e->name_len, s + e->name);
      size_t a0 = q;
      while (q < len && is_name_char(s[q]))
        q++;
      size_t a1 = q;
      while (q < len && is_ws(s[q]))
        q++;
      if (q >= len || s[q] != '=')
        FAIL_AT(v, a0, "attribute %.*s of <%.*s> has no value", (int)(a1 - a0), s + a0,
                (int)e->name_len, s + e->name);
      q++;
      while (q < len && is_ws(s[q]))
        q++;
      if (q >= len || (s[q] != '"' && s[q] != '\''))
        FAIL_AT(v, a0, "attribute %.*s of <%.*s>: value not quoted", (int)(a1 - a0), s + a0,
                (int)e->name_len, s + e->name);
      unsigned char quote = s[q++];
      size_t v0 = q;
      while (q < len && s[q] != quote && s[q] != '<')
        q++;
      if (q >= len || s[q] != quote)
        FAIL_AT(v, a0, "attribute %.*s of <%.*s>: unterminated value", (int)(a1 - a0), s + a0,
                (int)e->name_len, s + e->name);
      if (e->n_attrs == VTP_MAX_ATTRS)
        FAIL_AT(v, p, "<%.*s> has more than %d attributes", (int)e->name_len, s + e->name,
                VTP_MAX_ATTRS);
      for (int i = 0; i < e->n_attrs; i++)
        if (e->attrs[i].name_len == a1 - a0 && memcmp(s + e->attrs[i].name, s + a0, a1 - a0) == 0)
          FAIL_AT(v, a0, "attribute %.*s repeated in <%.*s>", (int)(a1 - a0), s + a0,
                  (int)e->name_len, s + e->name);
      e->attrs[e->n_attrs++] = (vattr_t){a0, a1 - a0, v0, q - v0};
      q++;
    }
    seen_root = 1;
    p = q;
    if (closed) continue;
    stack[depth++] = idx;
    text_of = idx;
    if (name_is(v, e, "AppendedData")) {
      /* Raw appended data may hold any byte: it runs from the '_' marker to
       * the last </AppendedData> of the file. */
      if (v->has_app) FAIL_EL(v, e, KARST_EPARSE, "a second AppendedData element");
      while (p < len && is_ws(s[p]))
        p++;
      if (p >= len || s[p] != '_')
        FAIL_EL(v, e, KARST_EPARSE, "the data does not start with the '_' marker");
      size_t start = p + 1, end = 0;
      for (size_t i = len; i >= start + 15; i--)
        if (memcmp(s + i - 15, "</AppendedData>", 15) == 0) {
          end = i - 15;
          break;
        }
      if (!end && !(len >= start + 15 && memcmp(s + start, "</AppendedData>", 15) == 0))
        FAIL_EL(v, e, KARST_EPARSE, "no </AppendedData> closes the data (truncated file?)");
      v->has_app = 1;
      v->app = start;
      v->app_len = end >= start ? end - start : 0;
      v->app_base64 = attr_is(v, e, "encoding", "base64");
      if (!v->app_base64 && !attr_is(v, e, "encoding", "raw"))
        FAIL_EL(v, e, KARST_EUNSUPPORTED, "encoding must be \"raw\" or \"base64\"");
      p = start + v->app_len;
      text_of = -1;
    }
  }
  if (depth > 0) {
    const velem_t *open = &v->el[stack[depth - 1]];
    FAIL_EL(v, open, KARST_EPARSE, "not closed before the end of the file (truncated file?)");
  }
  if (!seen_root) return karst_set_error(v->ctx, KARST_EPARSE, "%s: no XML element", v->file);
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Data: a byte source over base64 text or raw bytes                        */
/* ------------------------------------------------------------------------ */

typedef struct {
  const unsigned char *p;
  size_t n;
  int base64;
} vsrc_t;

static int b64_value(unsigned char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

/* Read up to @p n bytes at logical offset @p off of @p src into @p out (when
 * non-NULL); returns how many exist. Base64 is decoded group by group, and a
 * group with '=' padding yields 1 or 2 bytes and ends a chunk, so VTK's
 * separately encoded header and data chunks read as one stream.
 * Returns (size_t)-1 on a character that is not base64. O(off + n). */
static size_t src_read(const vsrc_t *src, uint64_t off, unsigned char *out, size_t n) {
  if (!src->base64) {
    if (off >= src->n) return 0;
    size_t k = src->n - off < n ? (size_t)(src->n - off) : n;
    if (out) memcpy(out, src->p + off, k);
    return k;
  }
  uint64_t pos = 0;
  size_t got = 0;
  int g[4], ng = 0;
  for (size_t i = 0; i < src->n && got < n; i++) {
    unsigned char c = src->p[i];
    if (is_ws(c)) continue;
    int val = c == '=' ? -2 : b64_value(c);
    if (val == -1) return (size_t)-1;
    g[ng++] = val;
    if (ng < 4) continue;
    ng = 0;
    if (g[0] < 0 || g[1] < 0 || (g[2] == -2 && g[3] != -2)) return (size_t)-1;
    unsigned char b[3];
    int nb = g[2] == -2 ? 1 : g[3] == -2 ? 2 : 3;
    b[0] = (unsigned char)(g[0] << 2 | g[1] >> 4);
    b[1] = (unsigned char)((g[1] & 15) << 4 | (g[2] > 0 ? g[2] >> 2 : 0));
    b[2] = (unsigned char)((g[2] > 0 ? (g[2] & 3) << 6 : 0) | (g[3] > 0 ? g[3] : 0));
    for (int k = 0; k < nb && got < n; k++, pos++)
      if (pos >= off) {
        if (out) out[got] = b[k];
        got++;
      }
  }
  return got;
}

static uint64_t word(const vc_t *v, const unsigned char *b) {
  int k = v->header64 ? 8 : 4;
  uint64_t x = 0;
  for (int i = 0; i < k; i++)
    x = x << 8 | b[v->big_endian ? i : k - 1 - i];
  return x;
}

/* An array's data as VTK will decode it. */
typedef struct {
  uint64_t bytes;        /* uncompressed bytes the header declares (checked against the file) */
  uint64_t nb, bs, last; /* compressed: block count, block size, last block size */
  uint64_t *csize;       /* compressed: size of each block */
  uint64_t data_off;     /* offset of the data (uncompressed) or of block 0 in the source */
  vsrc_t src;
} vdata_t;

static karst_error_t read_binary(vc_t *v, const velem_t *e, vsrc_t src, vdata_t *d) {
  const int hs = v->header64 ? 8 : 4;
  unsigned char h[24];
  memset(d, 0, sizeof *d);
  d->src = src;
  size_t total = src_read(&src, 0, NULL, SIZE_MAX);
  if (total == (size_t)-1) FAIL_EL(v, e, KARST_EPARSE, "the binary data is not valid base64");
  if (v->compressor == COMP_NONE) {
    if (src_read(&src, 0, h, (size_t)hs) < (size_t)hs)
      FAIL_EL(v, e, KARST_EPARSE, "the binary data ends inside its %d-byte header", hs);
    d->bytes = word(v, h);
    d->data_off = (uint64_t)hs;
    if (d->bytes > total - (size_t)hs)
      FAIL_EL(v, e, KARST_EPARSE,
              "the binary header declares %" PRIu64 " bytes; the file holds %zu after it", d->bytes,
              total - (size_t)hs);
    return KARST_SUCCESS;
  }
  if (src_read(&src, 0, h, (size_t)(3 * hs)) < (size_t)(3 * hs))
    FAIL_EL(v, e, KARST_EPARSE, "the compressed data ends inside its %d-byte header", 3 * hs);
  d->nb = word(v, h);
  d->bs = word(v, h + hs);
  d->last = word(v, h + 2 * hs);
  uint64_t room = (total - (size_t)(3 * hs)) / (size_t)hs;
  if (d->nb > room)
    FAIL_EL(v, e, KARST_EPARSE,
            "the compression header declares %" PRIu64
            " blocks; the file could hold at most %" PRIu64,
            d->nb, room);
  if (d->nb > 0 && d->bs == 0)
    FAIL_EL(v, e, KARST_EPARSE, "the compression header declares blocks of 0 bytes");
  if (d->last > d->bs)
    FAIL_EL(v, e, KARST_EPARSE,
            "the compression header's last block (%" PRIu64
            " bytes) is larger than its blocks (%" PRIu64 ")",
            d->last, d->bs);
  d->csize = malloc((size_t)(d->nb ? d->nb : 1) * sizeof *d->csize);
  unsigned char *raw = malloc((size_t)(d->nb ? d->nb : 1) * (size_t)hs);
  if (!d->csize || !raw) {
    free(raw);
    return karst_set_error(v->ctx, KARST_ENOMEM, "%s: out of memory", v->file);
  }
  size_t want = (size_t)d->nb * (size_t)hs;
  if (src_read(&src, (uint64_t)(3 * hs), raw, want) < want) {
    free(raw);
    FAIL_EL(v, e, KARST_EPARSE, "the compressed data ends inside its block sizes");
  }
  d->data_off = (uint64_t)(3 * hs) + want;
  uint64_t sum = 0;
  const uint64_t ratio = v->compressor == COMP_ZLIB  ? ZLIB_MAX_RATIO
                         : v->compressor == COMP_LZ4 ? LZ4_MAX_RATIO
                                                     : LZMA_MAX_RATIO;
  for (uint64_t i = 0; i < d->nb; i++) {
    d->csize[i] = word(v, raw + i * (size_t)hs);
    uint64_t u = (i + 1 == d->nb && d->last) ? d->last : d->bs;
    if (d->csize[i] > total || u > ratio * d->csize[i] + BLOCK_SLACK) {
      free(raw);
      FAIL_EL(v, e, KARST_EPARSE,
              "compressed block %" PRIu64 " declares %" PRIu64 " bytes from %" PRIu64
              " compressed bytes, more than the compressor can produce",
              i, u, d->csize[i]);
    }
    sum += d->csize[i];
    d->bytes += u;
  }
  free(raw);
  /* The block size is also what VTK allocates for one block: some block must
   * be able to produce it, or it stays within a small fixed allowance. */
  uint64_t most = VTP_BLOCK_SIZE_FLOOR;
  for (uint64_t i = 0; i < d->nb; i++)
    if (ratio * d->csize[i] + BLOCK_SLACK > most) most = ratio * d->csize[i] + BLOCK_SLACK;
  if (d->bs > most)
    FAIL_EL(v, e, KARST_EPARSE,
            "the compression header declares blocks of %" PRIu64
            " bytes, more than its compressed blocks can produce",
            d->bs);
  if (sum > total - d->data_off)
    FAIL_EL(v, e, KARST_EPARSE,
            "the compression header declares %" PRIu64 " compressed bytes; the file holds %" PRIu64,
            sum, (uint64_t)(total - d->data_off));
  return KARST_SUCCESS;
}

/* Bytes [off, off + n) of the uncompressed data of @p d into @p out. */
static karst_error_t data_bytes(vc_t *v, const velem_t *e, const vdata_t *d, uint64_t off,
                                unsigned char *out, size_t n) {
  if (off + n > d->bytes) FAIL_EL(v, e, KARST_EPARSE, "value outside the array's data");
  if (v->compressor == COMP_NONE) {
    if (src_read(&d->src, d->data_off + off, out, n) < n)
      FAIL_EL(v, e, KARST_EPARSE, "the binary data is truncated");
    return KARST_SUCCESS;
  }
  uint64_t b = off / d->bs, in = off % d->bs, coff = d->data_off;
  if (in + n > d->bs) FAIL_EL(v, e, KARST_EPARSE, "a value spans two compressed blocks");
  for (uint64_t i = 0; i < b; i++)
    coff += d->csize[i];
  uint64_t u = (b + 1 == d->nb && d->last) ? d->last : d->bs;
  unsigned char *cbuf = malloc((size_t)d->csize[b] + 1), *ubuf = malloc((size_t)u + 1);
  karst_error_t err = KARST_SUCCESS;
  if (!cbuf || !ubuf) {
    err = karst_set_error(v->ctx, KARST_ENOMEM, "%s: out of memory", v->file);
  } else if (src_read(&d->src, coff, cbuf, (size_t)d->csize[b]) < d->csize[b]) {
    char where[160];
    describe(v, e, where, sizeof where);
    err = karst_set_error(v->ctx, KARST_EPARSE, "%s: %s: compressed block %" PRIu64 " is truncated",
                          v->file, where, b);
  } else if (karst_i_vtk_uncompress(v->compressor, cbuf, (size_t)d->csize[b], ubuf, (size_t)u)) {
    char where[160];
    describe(v, e, where, sizeof where);
    err = karst_set_error(v->ctx, KARST_EPARSE,
                          "%s: %s: compressed block %" PRIu64 " does not decompress to %" PRIu64
                          " bytes",
                          v->file, where, b, u);
  } else {
    memcpy(out, ubuf + in, n);
  }
  free(cbuf);
  free(ubuf);
  return err;
}

/* ------------------------------------------------------------------------ */
/* Data arrays                                                              */
/* ------------------------------------------------------------------------ */

typedef struct {
  const char *name;
  int size; /* bytes per value; 0: bits (Bit), -1: String */
  int integral, is_signed;
} vtype_t;

static const vtype_t types[] = {
    {"Int8", 1, 1, 1},    {"UInt8", 1, 1, 0},   {"Int16", 2, 1, 1},   {"UInt16", 2, 1, 0},
    {"Int32", 4, 1, 1},   {"UInt32", 4, 1, 0},  {"Int64", 8, 1, 1},   {"UInt64", 8, 1, 0},
    {"Float32", 4, 0, 1}, {"Float64", 8, 0, 1}, {"String", -1, 0, 0}, {"Bit", 0, 1, 0},
    {"Char", 1, 1, 1},    {"UChar", 1, 1, 0},   {"IdType", 8, 1, 1},
};

/* What a DataArray holds: its values present and, on request, one integer. */
typedef struct {
  const vtype_t *type;
  uint64_t nc;
  uint64_t values; /* values (numbers, bits, or string bytes) its data holds */
  int want_at;     /* fetch the value at index `at` into `value` */
  uint64_t at;
  int64_t value;
  int finite; /* check ASCII values are finite numbers */
} varr_t;

static karst_error_t check_array(vc_t *v, const velem_t *e, varr_t *a) {
  karst_error_t err;
  const char *s;
  size_t n;
  if (!attr(v, e, "type", &s, &n)) FAIL_EL(v, e, KARST_EPARSE, "no type attribute");
  a->type = NULL;
  for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
    if (strlen(types[i].name) == n && memcmp(types[i].name, s, n) == 0) a->type = &types[i];
  if (!a->type)
    FAIL_EL(v, e, KARST_EUNSUPPORTED, "unknown type \"%.*s\"", (int)(n > 40 ? 40 : n), s);
  int r = attr_count(v, e, "NumberOfComponents", 1, &a->nc);
  if (r < 0) FAIL_EL(v, e, KARST_EPARSE, "NumberOfComponents is not a whole number");
  if (a->nc < 1 || a->nc > VTP_MAX_COMPONENTS)
    FAIL_EL(v, e, KARST_ERANGE, "NumberOfComponents is %" PRIu64 "; it must be 1 to %d", a->nc,
            VTP_MAX_COMPONENTS);
  if (!attr(v, e, "format", &s, &n)) FAIL_EL(v, e, KARST_EPARSE, "no format attribute");
  const int vsize = a->type->size > 0 ? a->type->size : 1;
  if (n == 5 && memcmp(s, "ascii", 5) == 0) {
    /* Count the tokens; fetch one, check finiteness. */
    uint64_t k = 0;
    const char *t = (const char *)v->s + e->text, *end = t + e->text_len;
    while (t < end) {
      while (t < end && is_ws((unsigned char)*t))
        t++;
      if (t >= end) break;
      const char *t0 = t;
      while (t < end && !is_ws((unsigned char)*t))
        t++;
      if ((a->finite && !a->type->integral) || (a->want_at && k == a->at)) {
        char tok[64];
        size_t tl = (size_t)(t - t0) < sizeof tok - 1 ? (size_t)(t - t0) : sizeof tok - 1;
        memcpy(tok, t0, tl);
        tok[tl] = '\0';
        char *ep;
        double x = strtod(tok, &ep);
        if (ep == tok || *ep || !isfinite(x))
          FAIL_EL(v, e, KARST_EPARSE, "value %" PRIu64 " ('%s') is not a finite number", k, tok);
        if (a->want_at && k == a->at) {
          if (x != floor(x) || fabs(x) > 9e18)
            FAIL_EL(v, e, KARST_EPARSE, "value %" PRIu64 " ('%s') is not a whole number", k, tok);
          a->value = (int64_t)x;
        }
      }
      k++;
    }
    a->values = k;
  } else if ((n == 6 && memcmp(s, "binary", 6) == 0) || (n == 8 && memcmp(s, "appended", 8) == 0)) {
    vsrc_t src;
    if (n == 6) {
      src = (vsrc_t){v->s + e->text, e->text_len, 1};
    } else {
      uint64_t off;
      if (!v->has_app)
        FAIL_EL(v, e, KARST_EPARSE, "format=\"appended\" but the file has no AppendedData");
      if (attr_count(v, e, "offset", 0, &off) != 1)
        FAIL_EL(v, e, KARST_EPARSE, "no valid offset attribute");
      if (off >= v->app_len && !(off == 0 && v->app_len == 0))
        FAIL_EL(v, e, KARST_EPARSE, "offset %" PRIu64 " is past the %zu bytes of AppendedData", off,
                v->app_len);
      src = (vsrc_t){v->s + v->app + off, v->app_len - (size_t)off, v->app_base64};
    }
    vdata_t d;
    err = read_binary(v, e, src, &d);
    if (!err) {
      a->values = a->type->size == 0 ? d.bytes * 8 : d.bytes / (uint64_t)vsize;
      if (a->want_at && a->at < a->values && a->type->integral && a->type->size > 0) {
        unsigned char b[8];
        if (!(err = data_bytes(v, e, &d, a->at * (uint64_t)vsize, b, (size_t)vsize))) {
          uint64_t x = 0;
          for (int i = 0; i < vsize; i++)
            x = x << 8 | b[v->big_endian ? i : vsize - 1 - i];
          if (a->type->is_signed && vsize < 8 && (x >> (8 * vsize - 1)) & 1)
            x |= ~(uint64_t)0 << (8 * vsize);
          a->value = (int64_t)x;
        }
      }
    }
    free(d.csize);
    if (err) return err;
  } else {
    FAIL_EL(v, e, KARST_EUNSUPPORTED, "format \"%.*s\" (expected ascii, binary or appended)",
            (int)(n > 20 ? 20 : n), s);
  }
  return KARST_SUCCESS;
}

/* Check data array @p e holds @p tuples tuples (0 with !known: any). */
static karst_error_t check_counted(vc_t *v, const velem_t *e, int known, uint64_t tuples,
                                   int finite) {
  varr_t a;
  memset(&a, 0, sizeof a);
  a.finite = finite;
  karst_error_t err = check_array(v, e, &a);
  if (err) return err;
  if (a.type->size < 0 && known && tuples > a.values) /* strings: at least a NUL each */
    FAIL_EL(v, e, KARST_EPARSE, "declares %" PRIu64 " strings; its data holds %" PRIu64 " bytes",
            tuples, a.values);
  if (a.type->size >= 0 && known) {
    if (tuples > UINT64_MAX / a.nc || tuples * a.nc > a.values)
      FAIL_EL(v, e, KARST_EPARSE,
              "needs %" PRIu64 " tuples of %" PRIu64 " components; its data holds %" PRIu64
              " values",
              tuples, a.nc, a.values);
  }
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Structure                                                                */
/* ------------------------------------------------------------------------ */

static const char *const cell_kinds[4] = {"Verts", "Lines", "Strips", "Polys"};
static const char *const cell_counts[4] = {"NumberOfVerts", "NumberOfLines", "NumberOfStrips",
                                           "NumberOfPolys"};

/* The first child of @p parent named @p name after index @p from, or -1. */
static int child(const vc_t *v, int parent, const char *name, int from) {
  for (int i = from + 1; i < v->n_el; i++)
    if (v->el[i].parent == parent && name_is(v, &v->el[i], name)) return i;
  return -1;
}

static int count_children(const vc_t *v, int parent, const char *name) {
  int k = 0;
  for (int i = child(v, parent, name, parent); i >= 0; i = child(v, parent, name, i))
    k++;
  return k;
}

/* DataArray @p name among the children of @p parent, or -1. */
static int named_array(const vc_t *v, int parent, const char *name) {
  for (int i = child(v, parent, "DataArray", parent); i >= 0; i = child(v, parent, "DataArray", i))
    if (attr_is(v, &v->el[i], "Name", name)) return i;
  return -1;
}

static karst_error_t check_cells(vc_t *v, int piece, int kind, uint64_t count) {
  const velem_t *pe = &v->el[piece];
  int c = child(v, piece, cell_kinds[kind], piece);
  if (count_children(v, piece, cell_kinds[kind]) > 1)
    FAIL_EL(v, pe, KARST_EPARSE, "more than one <%s>", cell_kinds[kind]);
  if (c < 0) {
    if (count > 0)
      FAIL_EL(v, pe, KARST_EPARSE, "%s is %" PRIu64 " but the piece has no <%s>", cell_counts[kind],
              count, cell_kinds[kind]);
    return KARST_SUCCESS;
  }
  int conn = named_array(v, c, "connectivity"), offs = named_array(v, c, "offsets");
  if ((conn < 0 || offs < 0) && count > 0)
    FAIL_EL(v, &v->el[c], KARST_EPARSE, "no DataArray named \"%s\" for its %" PRIu64 " cells",
            conn < 0 ? "connectivity" : "offsets", count);
  karst_error_t err;
  varr_t ca, oa;
  memset(&ca, 0, sizeof ca);
  memset(&oa, 0, sizeof oa);
  if (conn >= 0 && (err = check_array(v, &v->el[conn], &ca))) return err;
  if (offs < 0) return KARST_SUCCESS;
  /* VTK reads NumberOfCells offsets (NumberOfCells + 1, from 0, in version 2
   * files) and sizes the connectivity from the last one. */
  uint64_t need = count + (v->version_major >= 2 ? 1 : 0);
  oa.want_at = count > 0;
  oa.at = need - 1;
  if ((err = check_array(v, &v->el[offs], &oa))) return err;
  if (count == 0) return KARST_SUCCESS;
  if (!oa.type->integral || oa.type->size <= 0)
    FAIL_EL(v, &v->el[offs], KARST_EPARSE, "offsets must be integers");
  if (!ca.type->integral || ca.type->size <= 0)
    FAIL_EL(v, &v->el[conn], KARST_EPARSE, "connectivity must be integers");
  if (oa.nc != 1 || ca.nc != 1)
    FAIL_EL(v, &v->el[oa.nc != 1 ? offs : conn], KARST_EPARSE, "cell arrays have one component");
  if (oa.values < need)
    FAIL_EL(v, &v->el[offs], KARST_EPARSE,
            "%s is %" PRIu64 " but the offsets hold %" PRIu64 " values", cell_counts[kind], count,
            oa.values);
  if (oa.value < 0 || (uint64_t)oa.value > ca.values)
    FAIL_EL(v, &v->el[offs], KARST_EPARSE,
            "the last offset is %" PRId64 "; the connectivity holds %" PRIu64 " values", oa.value,
            ca.values);
  return KARST_SUCCESS;
}

static karst_error_t check_piece(vc_t *v, int piece) {
  const velem_t *pe = &v->el[piece];
  karst_error_t err;
  uint64_t np, nc[4], ncells = 0;
  /* At most one value per byte of the file, times the best ratio of its compressor. */
  const uint64_t ratio = v->compressor == COMP_NONE   ? 1
                         : v->compressor == COMP_ZLIB ? ZLIB_MAX_RATIO
                         : v->compressor == COMP_LZ4  ? LZ4_MAX_RATIO
                                                      : LZMA_MAX_RATIO;
  const uint64_t cap = (uint64_t)v->len * ratio + BLOCK_SLACK;
  if (attr_count(v, pe, "NumberOfPoints", 0, &np) < 0)
    FAIL_EL(v, pe, KARST_EPARSE, "NumberOfPoints is not a whole number");
  if (np > cap)
    FAIL_EL(v, pe, KARST_ERANGE, "NumberOfPoints is %" PRIu64 ", more than a %zu-byte file holds",
            np, v->len);
  for (int k = 0; k < 4; k++) {
    if (attr_count(v, pe, cell_counts[k], 0, &nc[k]) < 0)
      FAIL_EL(v, pe, KARST_EPARSE, "%s is not a whole number", cell_counts[k]);
    if (nc[k] > cap)
      FAIL_EL(v, pe, KARST_ERANGE, "%s is %" PRIu64 ", more than a %zu-byte file holds",
              cell_counts[k], nc[k], v->len);
    ncells += nc[k];
  }
  static const char *const once[] = {"PointData", "CellData", "Points"};
  for (int k = 0; k < 3; k++)
    if (count_children(v, piece, once[k]) > 1)
      FAIL_EL(v, pe, KARST_EPARSE, "more than one <%s>", once[k]);
  int pts = child(v, piece, "Points", piece);
  if (np > 0) {
    if (pts < 0)
      FAIL_EL(v, pe, KARST_EPARSE, "NumberOfPoints is %" PRIu64 " but the piece has no <Points>",
              np);
    int a = child(v, pts, "DataArray", pts);
    if (a < 0) FAIL_EL(v, &v->el[pts], KARST_EPARSE, "no DataArray for the %" PRIu64 " points", np);
    varr_t pa;
    memset(&pa, 0, sizeof pa);
    pa.finite = 1;
    if ((err = check_array(v, &v->el[a], &pa))) return err;
    if (pa.type->size <= 0)
      FAIL_EL(v, &v->el[a], KARST_EPARSE, "points must be numbers, not %s", pa.type->name);
    if (pa.nc != 3)
      FAIL_EL(v, &v->el[a], KARST_EPARSE, "points have 3 components, not %" PRIu64, pa.nc);
    if ((err = check_counted(v, &v->el[a], 1, np, 1))) return err;
  }
  for (int k = 0; k < 4; k++)
    if ((err = check_cells(v, piece, k, nc[k]))) return err;
  for (int dom = 0; dom < 2; dom++) {
    int d = child(v, piece, dom ? "CellData" : "PointData", piece);
    if (d < 0) continue;
    for (int a = child(v, d, "DataArray", d); a >= 0; a = child(v, d, "DataArray", a))
      if ((err = check_counted(v, &v->el[a], 1, dom ? ncells : np, 0))) return err;
  }
  return KARST_SUCCESS;
}

static karst_error_t check_structure(vc_t *v) {
  karst_error_t err;
  const velem_t *root = &v->el[0];
  if (!name_is(v, root, "VTKFile"))
    FAIL_EL(v, root, KARST_EPARSE, "not a VTK XML file (expected <VTKFile type=\"PolyData\">)");
  if (!attr_is(v, root, "type", "PolyData"))
    FAIL_EL(v, root, KARST_EPARSE, "not a VTK XML PolyData file (expected type=\"PolyData\")");
  v->big_endian = attr_is(v, root, "byte_order", "BigEndian");
  const char *s;
  size_t n;
  if (attr(v, root, "byte_order", &s, &n) && !v->big_endian &&
      !attr_is(v, root, "byte_order", "LittleEndian"))
    FAIL_EL(v, root, KARST_EUNSUPPORTED, "byte_order must be LittleEndian or BigEndian");
  v->header64 = attr_is(v, root, "header_type", "UInt64");
  if (attr(v, root, "header_type", &s, &n) && !v->header64 &&
      !attr_is(v, root, "header_type", "UInt32"))
    FAIL_EL(v, root, KARST_EUNSUPPORTED, "header_type must be UInt32 or UInt64");
  v->compressor = COMP_NONE;
  if (attr(v, root, "compressor", &s, &n)) {
    if (attr_is(v, root, "compressor", "vtkZLibDataCompressor"))
      v->compressor = COMP_ZLIB;
    else if (attr_is(v, root, "compressor", "vtkLZ4DataCompressor"))
      v->compressor = COMP_LZ4;
    else if (attr_is(v, root, "compressor", "vtkLZMADataCompressor"))
      v->compressor = COMP_LZMA;
    else
      FAIL_EL(v, root, KARST_EUNSUPPORTED,
              "compressor \"%.*s\" is not read (VTK writes vtkZLibDataCompressor, "
              "vtkLZ4DataCompressor or vtkLZMADataCompressor)",
              (int)(n > 40 ? 40 : n), s);
  }
  v->version_major = 0;
  if (attr(v, root, "version", &s, &n)) v->version_major = atoi(s);
  if (count_children(v, 0, "PolyData") != 1)
    FAIL_EL(v, root, KARST_EPARSE, "must hold exactly one <PolyData>");
  int pd = child(v, 0, "PolyData", 0);
  if (count_children(v, pd, "Piece") < 1) FAIL_EL(v, &v->el[pd], KARST_EPARSE, "holds no <Piece>");
  for (int i = 0; i < v->n_el; i++) {
    const velem_t *e = &v->el[i];
    if (!name_is(v, e, "FieldData")) continue;
    for (int a = child(v, i, "DataArray", i); a >= 0; a = child(v, i, "DataArray", a)) {
      uint64_t t;
      int r = attr_count(v, &v->el[a], "NumberOfTuples", 0, &t);
      if (r < 0) FAIL_EL(v, &v->el[a], KARST_EPARSE, "NumberOfTuples is not a whole number");
      if ((err = check_counted(v, &v->el[a], r == 1, t, 0))) return err;
    }
  }
  for (int p = child(v, pd, "Piece", pd); p >= 0; p = child(v, pd, "Piece", p))
    if ((err = check_piece(v, p))) return err;
  return KARST_SUCCESS;
}

karst_error_t karst_i_vtp_check_buffer(karst_ctx_t *ctx, const char *name,
                                       const unsigned char *data, size_t len) {
  vc_t v;
  memset(&v, 0, sizeof v);
  v.ctx = ctx;
  v.file = name;
  v.s = data;
  v.len = len;
  karst_error_t err = parse_xml(&v);
  if (!err) err = check_structure(&v);
  free(v.el);
  return err;
}

karst_error_t karst_i_vtp_check(karst_ctx_t *ctx, const char *path) {
  unsigned char *data;
  size_t len;
  karst_error_t err = karst_i_read_regular(ctx, path, ".vtp", KARST_VTP_MAX_BYTES, &data, &len);
  if (err) return err;
  err = karst_i_vtp_check_buffer(ctx, path, data, len);
  free(data);
  return err;
}
