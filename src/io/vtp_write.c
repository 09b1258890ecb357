/* VTK XML PolyData written without VTK (vtp_write_internal.h).
 *
 * Format: "VTK File Formats", VTK User's Guide (Kitware), "XML File Formats": inline binary
 * data is base64 text of a header of UInt64 words (number of blocks, block size, size of the
 * last partial block, then each block's compressed size), followed, as a second base64 text,
 * by the blocks, each compressed on its own with zlib. The layout details below (element and
 * attribute order, indentation, ranges, information keys) are those of VTK 9.1's
 * vtkXMLPolyDataWriter, checked byte for byte by tests/unit/test_vtp_write.c. Like VTK's
 * writer it streams: an array's header is written as a placeholder and filled in once its
 * blocks are compressed, so a file needs the memory of one block, not of the file. */
#include "io/vtp_write_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "karst/io.h"

/** VTK's block size for compressed data. */
#define VTP_BLOCK 32768
/** VTK_DOUBLE_MAX (vtkType.h): the range VTK reports for an array with no values. */
#define VTP_EMPTY_RANGE 1.0e+299

/* ------------------------------------------------------------------------ */
/* The file, written through a buffer                                         */
/* ------------------------------------------------------------------------ */

/** The buffer is written out when full: a file's memory is that of one array's data, not the
 *  whole file's (a mesh of 19 M triangles writes a 500 MB .vtp). 64 KiB, as the stream karst
 *  gave VTK's writer: with 1 MiB, an ensemble of 100 branchwork members on 2 threads peaked at
 *  194–214 MiB resident, with 64 KiB at 178–188 MiB (VTK's writer: 135–143 MiB; the heap's own
 *  peak is the same, docs/performance.md). */
#define VB_CAPACITY ((size_t)1 << 16)

typedef struct {
  char *p;
  size_t n, cap;
  int fd;
  uint64_t off; /* file offset of p[0] */
  int failed;   /* 1: out of memory, 2: write error (errno in err) */
  int err;
} vbuf_t;

/* Write @p n bytes at file offset @p pos, retrying short writes; a failure sets b->failed. */
static void vb_write_at(vbuf_t *b, const char *s, size_t n, uint64_t pos) {
  while (n > 0 && !b->failed) {
    ssize_t w = pwrite(b->fd, s, n, (off_t)pos);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      b->failed = 2, b->err = w < 0 ? errno : EIO;
      return;
    }
    s += w, n -= (size_t)w, pos += (uint64_t)w;
  }
}

static void vb_flush(vbuf_t *b) {
  vb_write_at(b, b->p, b->n, b->off);
  if (b->failed) return;
  b->off += b->n;
  b->n = 0;
}

static int vb_reserve(vbuf_t *b, size_t more) {
  if (b->failed) return -1;
  if (b->n + more <= b->cap) return 0;
  if (b->n > 0) vb_flush(b);
  if (b->failed) return -1;
  if (more <= b->cap) return 0;
  size_t cap = b->cap > VB_CAPACITY ? b->cap : VB_CAPACITY;
  while (cap < more) {
    if (cap > SIZE_MAX / 2) {
      b->failed = 1;
      return -1;
    }
    cap *= 2;
  }
  char *p = realloc(b->p, cap);
  if (!p) {
    b->failed = 1;
    return -1;
  }
  b->p = p, b->cap = cap;
  return 0;
}

static void vb_put(vbuf_t *b, const char *s, size_t n) {
  if (vb_reserve(b, n)) return;
  memcpy(b->p + b->n, s, n);
  b->n += n;
}

/* Overwrite @p n bytes at file offset @p pos (written earlier: in the file, in the buffer, or
 * partly in each). */
static void vb_patch(vbuf_t *b, uint64_t pos, const char *s, size_t n) {
  if (pos < b->off) { /* the part already in the file */
    size_t k = (size_t)(b->off - pos) < n ? (size_t)(b->off - pos) : n;
    vb_write_at(b, s, k, pos);
    s += k, n -= k, pos += k;
  }
  if (n > 0 && !b->failed) memcpy(b->p + (pos - b->off), s, n);
}

static void vb_str(vbuf_t *b, const char *s) { vb_put(b, s, strlen(s)); }

static void vb_indent(vbuf_t *b, int indent) {
  if (vb_reserve(b, (size_t)indent)) return;
  memset(b->p + b->n, ' ', (size_t)indent);
  b->n += (size_t)indent;
}

static void vb_printf(vbuf_t *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void vb_printf(vbuf_t *b, const char *fmt, ...) {
  char tmp[128];
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
  va_end(ap);
  if (n < 0) {
    b->failed = 1;
    return;
  }
  if ((size_t)n < sizeof tmp) {
    vb_put(b, tmp, (size_t)n);
    return;
  }
  if (vb_reserve(b, (size_t)n + 1)) return;
  va_start(ap, fmt);
  vsnprintf(b->p + b->n, (size_t)n + 1, fmt, ap);
  va_end(ap);
  b->n += (size_t)n;
}

/* An attribute value: VTK writes names as they are; karst's names never hold the characters
 * XML reserves, and any that did are escaped here so the file stays well-formed. */
static void vb_attr_text(vbuf_t *b, const char *s) {
  for (; *s; s++) {
    switch (*s) {
    case '&': vb_str(b, "&amp;"); break;
    case '<': vb_str(b, "&lt;"); break;
    case '>': vb_str(b, "&gt;"); break;
    case '"': vb_str(b, "&quot;"); break;
    default: vb_put(b, s, 1);
    }
  }
}

/* ------------------------------------------------------------------------ */
/* Numbers                                                                   */
/* ------------------------------------------------------------------------ */

/* Digits of @p d (> 0, finite) with @p p significant digits, the one nearest (printf's
 * correct rounding): mantissa *m (p digits) and decimal exponent *e of its first digit. */
static void digits_nearest(double d, int p, uint64_t *m, int *e) {
  char s[40];
  snprintf(s, sizeof s, "%.*e", p - 1, d);
  uint64_t v = 0;
  const char *c = s;
  for (; *c && *c != 'e'; c++)
    if (*c >= '0' && *c <= '9') v = v * 10 + (uint64_t)(*c - '0');
  *m = v;
  *e = atoi(c + 1);
}

/* Value of mantissa @p m times 10^(e - digits(m) + 1)... as the double strtod gives for
 * "m e x" with the mantissa an integer: exact decimal to correctly rounded binary. */
static double digits_value(uint64_t m, int x) {
  char s[48];
  snprintf(s, sizeof s, "%" PRIu64 "e%d", m, x);
  return strtod(s, NULL);
}

int karst_i_vtp_format_shortest(double v, char *buf) {
  if (v != v) return sprintf(buf, "NaN");
  if (isinf(v)) return sprintf(buf, v < 0 ? "-Infinity" : "Infinity");
  if (v == 0) return sprintf(buf, "0"); /* UNIQUE_ZERO: -0 too */
  int neg = v < 0;
  double d = neg ? -v : v;
  /* The shortest digit string that reads back as d; of two such strings of that length, the
   * nearer. The nearest p-digit string is tried first; at a power of two the interval of
   * values reading back as d is lopsided, and the neighbour of the nearest on the other side
   * of d may lie within it when the nearest does not. */
  uint64_t m = 0;
  int e = 0;
  for (int p = 1; p <= 17; p++) {
    uint64_t mn;
    int en;
    digits_nearest(d, p, &mn, &en);
    int x = en - (p - 1); /* value = mn 10^x */
    if (digits_value(mn, x) == d) {
      m = mn, e = x;
      break;
    }
    /* The interval holds d, and the nearest lies outside it on one side: a neighbour further
     * out on that side cannot lie inside, so at most one of the two reads back. */
    for (int s = -1; s <= 1 && !m; s += 2) {
      uint64_t mc = s < 0 ? mn - 1 : mn + 1;
      if (mc != 0 && digits_value(mc, x) == d) m = mc, e = x;
    }
    if (m) break;
  }
  if (!m) { /* cannot happen: 17 digits always read back */
    return sprintf(buf, "%.17g", v);
  }
  while (m % 10 == 0)
    m /= 10, e++;
  char dig[24];
  int n = sprintf(dig, "%" PRIu64, m);
  int point = n + e; /* value = 0.dig × 10^point */
  int exponent = point - 1;
  char *o = buf;
  if (neg) *o++ = '-';
  if (exponent >= -6 && exponent < 21) {
    if (point <= 0) {
      *o++ = '0', *o++ = '.';
      for (int i = 0; i < -point; i++)
        *o++ = '0';
      memcpy(o, dig, (size_t)n), o += n;
    } else if (point >= n) {
      memcpy(o, dig, (size_t)n), o += n;
      for (int i = n; i < point; i++)
        *o++ = '0';
    } else {
      memcpy(o, dig, (size_t)point), o += point;
      *o++ = '.';
      memcpy(o, dig + point, (size_t)(n - point)), o += n - point;
    }
  } else {
    *o++ = dig[0];
    if (n > 1) {
      *o++ = '.';
      memcpy(o, dig + 1, (size_t)(n - 1)), o += n - 1;
    }
    o += sprintf(o, "e%s%d", exponent >= 0 ? "+" : "", exponent);
  }
  *o = '\0';
  return (int)(o - buf);
}

/* ------------------------------------------------------------------------ */
/* Binary data: zlib blocks, base64                                           */
/* ------------------------------------------------------------------------ */

static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/* Base64 of @p n bytes into @p o (4 ceil(n / 3) characters, '=' padded). @return the end. */
static char *base64(char *o, const unsigned char *s, size_t n) {
  size_t i = 0;
  for (; i + 3 <= n; i += 3) {
    uint32_t w = (uint32_t)s[i] << 16 | (uint32_t)s[i + 1] << 8 | s[i + 2];
    *o++ = b64[w >> 18], *o++ = b64[(w >> 12) & 63], *o++ = b64[(w >> 6) & 63],
    *o++ = b64[w & 63];
  }
  if (i < n) {
    uint32_t w = (uint32_t)s[i] << 16 | (i + 1 < n ? (uint32_t)s[i + 1] << 8 : 0);
    *o++ = b64[w >> 18], *o++ = b64[(w >> 12) & 63];
    *o++ = i + 1 < n ? b64[(w >> 6) & 63] : '=';
    *o++ = '=';
  }
  return o;
}

/* The blocks' base64 is one text across the blocks: 0 to 2 bytes wait for the next block. */
typedef struct {
  unsigned char carry[2];
  int n_carry;
} b64_stream_t;

static void vb_base64_stream(vbuf_t *b, b64_stream_t *st, const unsigned char *s, size_t n) {
  unsigned char head[3];
  int h = st->n_carry;
  memcpy(head, st->carry, (size_t)h);
  while (h < 3 && n > 0)
    head[h++] = *s++, n--;
  if (h < 3) { /* still not a whole group */
    memcpy(st->carry, head, (size_t)h);
    st->n_carry = h;
    return;
  }
  size_t whole = n / 3 * 3;
  if (vb_reserve(b, 4 + whole / 3 * 4)) return;
  char *o = base64(b->p + b->n, head, 3);
  o = base64(o, s, whole);
  b->n = (size_t)(o - b->p);
  st->n_carry = (int)(n - whole);
  memcpy(st->carry, s + whole, (size_t)st->n_carry);
}

static void vb_base64_end(vbuf_t *b, b64_stream_t *st) {
  if (st->n_carry == 0 || vb_reserve(b, 4)) return;
  b->n = (size_t)(base64(b->p + b->n, st->carry, (size_t)st->n_carry) - b->p);
  st->n_carry = 0;
}

/* The raw bytes of one array, compressed in VTK's blocks and written as base64: the header
 * (number of blocks, block size, last partial block's size, each block's compressed size) is
 * written as a placeholder of its final length, the blocks are compressed and written one by
 * one, and the header is then filled in. @return 0, or -1 on failure (b->failed set). */
static int vb_binary(vbuf_t *b, const unsigned char *raw, size_t n) {
  size_t nb = n / VTP_BLOCK + (n % VTP_BLOCK ? 1 : 0);
  size_t hbytes = 8 * (3 + nb), hlen = (hbytes + 2) / 3 * 4;
  uint64_t *hdr = malloc(hbytes);
  char *htext = malloc(hlen);
  uLong bound = compressBound(VTP_BLOCK);
  unsigned char *z = malloc(bound);
  if (!hdr || !htext || !z || vb_reserve(b, hlen)) {
    free(hdr), free(htext), free(z);
    if (!b->failed) b->failed = 1;
    return -1;
  }
  const uint64_t hpos = b->off + b->n;
  memset(b->p + b->n, 'A', hlen);
  b->n += hlen;
  hdr[0] = nb, hdr[1] = VTP_BLOCK, hdr[2] = n % VTP_BLOCK;
  b64_stream_t st = {{0, 0}, 0};
  for (size_t k = 0; k < nb && !b->failed; k++) {
    size_t len = k + 1 < nb || n % VTP_BLOCK == 0 ? VTP_BLOCK : n % VTP_BLOCK;
    uLongf out = bound;
    if (compress2(z, &out, raw + k * VTP_BLOCK, (uLong)len, KARST_I_VTP_ZLIB_LEVEL) != Z_OK) {
      b->failed = 1;
      break;
    }
    hdr[3 + k] = out;
    vb_base64_stream(b, &st, z, out);
  }
  vb_base64_end(b, &st);
  /* the header's words, little-endian (the file says byte_order="LittleEndian") */
  unsigned char *hb = (unsigned char *)hdr;
  for (size_t i = 0; i < 3 + nb; i++) {
    uint64_t w = hdr[i];
    for (int j = 0; j < 8; j++)
      hb[8 * i + (size_t)j] = (unsigned char)(w >> (8 * j));
  }
  base64(htext, hb, hbytes);
  vb_patch(b, hpos, htext, hlen);
  free(hdr), free(htext), free(z);
  return b->failed ? -1 : 0;
}

/* An array's bytes as the file stores them: the values themselves (little-endian, the
 * machine's order: the build refuses other machines below), or for strings a copy of each
 * followed by a NUL (*copy set, to be freed). */
static const unsigned char *array_bytes(const karst_i_vtp_array_t *a, size_t *n,
                                        unsigned char **copy) {
  size_t count = (size_t)a->n * (size_t)a->ncomp;
  *copy = NULL;
  if (a->type != KARST_I_VTP_STRING) {
    static const unsigned char none[1] = {0};
    *n = count * (a->type == KARST_I_VTP_INT32 ? 4 : 8);
    return *n ? (const unsigned char *)a->data : none;
  }
  const char *const *s = a->data;
  size_t len = 0;
  for (size_t i = 0; i < count; i++)
    len += (s && s[i] ? strlen(s[i]) : 0) + 1;
  unsigned char *r = malloc(len ? len : 1);
  if (!r) return NULL;
  size_t at = 0;
  for (size_t i = 0; i < count; i++) {
    size_t l = s && s[i] ? strlen(s[i]) : 0;
    if (l) memcpy(r + at, s[i], l);
    at += l;
    r[at++] = 0;
  }
  *n = len;
  *copy = r;
  return r;
}

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "vtp_write.c writes the machine's bytes as little-endian: port it to this machine"
#endif

static double value_at(const karst_i_vtp_array_t *a, size_t i) {
  switch (a->type) {
  case KARST_I_VTP_INT32: return (double)((const int32_t *)a->data)[i];
  case KARST_I_VTP_INT64: return (double)((const int64_t *)a->data)[i];
  default: return ((const double *)a->data)[i];
  }
}

/* VTK's range of a numeric array: of its values for one component, of the tuples' Euclidean
 * norms for several; NaN skipped; no values: (1e299, -1e299). */
static void array_range(const karst_i_vtp_array_t *a, double r[2]) {
  r[0] = VTP_EMPTY_RANGE, r[1] = -VTP_EMPTY_RANGE;
  int nc = a->ncomp;
  for (karst_int_t t = 0; t < a->n; t++) {
    double s;
    if (nc == 1) {
      s = value_at(a, (size_t)t);
    } else {
      s = 0;
      for (int c = 0; c < nc; c++) {
        double v = value_at(a, (size_t)t * (size_t)nc + (size_t)c);
        s += v * v;
      }
    }
    if (s != s) continue;
    if (s < r[0]) r[0] = s;
    if (s > r[1]) r[1] = s;
  }
  if (nc > 1 && a->n > 0 && r[0] <= r[1]) r[0] = sqrt(r[0]), r[1] = sqrt(r[1]);
}

static const char *type_name(karst_i_vtp_type_t t) {
  switch (t) {
  case KARST_I_VTP_INT32: return "Int32";
  case KARST_I_VTP_INT64: return "Int64";
  case KARST_I_VTP_FLOAT64: return "Float64";
  default: return "String";
  }
}

static void vb_shortest(vbuf_t *b, const char *name, double v) {
  char s[40];
  karst_i_vtp_format_shortest(v, s);
  vb_printf(b, " %s=\"%s\"", name, s);
}

/* One array element: "Array" for strings, "DataArray" for numbers; in field data with its
 * number of tuples. */
static int put_array(vbuf_t *b, int indent, const karst_i_vtp_array_t *a, int in_field) {
  const int str = a->type == KARST_I_VTP_STRING;
  const char *tag = str ? "Array" : "DataArray";
  vb_indent(b, indent);
  vb_printf(b, "<%s type=\"%s\" Name=\"", tag, type_name(a->type));
  vb_attr_text(b, a->name);
  vb_str(b, "\"");
  if (a->ncomp > 1) vb_printf(b, " NumberOfComponents=\"%d\"", a->ncomp);
  if (a->comp_names)
    for (int c = 0; c < a->ncomp; c++)
      if (a->comp_names[c]) {
        vb_printf(b, " ComponentName%d=\"", c);
        vb_attr_text(b, a->comp_names[c]);
        vb_str(b, "\"");
      }
  if (in_field) vb_printf(b, " NumberOfTuples=\"%" PRId64 "\"", (int64_t)a->n);
  vb_str(b, " format=\"binary\"");
  double r[2] = {0, 0};
  if (!str) {
    array_range(a, r);
    vb_shortest(b, "RangeMin", r[0]);
    vb_shortest(b, "RangeMax", r[1]);
  }
  vb_str(b, ">\n");
  size_t n = 0;
  unsigned char *copy;
  const unsigned char *raw = array_bytes(a, &n, &copy);
  if (!raw) {
    b->failed = 1;
    return -1;
  }
  vb_indent(b, indent + 2);
  vb_binary(b, raw, n);
  free(copy);
  vb_str(b, "\n");
  if (!str && a->ncomp > 1) { /* GetRange(-1) caches the norms' range in the array;
                                VTK writes this key before UNITS_LABEL */
    vb_indent(b, indent + 2);
    vb_str(b, "<InformationKey name=\"L2_NORM_RANGE\" location=\"vtkDataArray\" length=\"2\">\n");
    for (int i = 0; i < 2; i++) {
      vb_indent(b, indent + 4);
      vb_printf(b, "<Value index=\"%d\">\n", i);
      vb_indent(b, indent + 6);
      vb_printf(b, "%.11g\n", r[i]);
      vb_indent(b, indent + 4);
      vb_str(b, "</Value>\n");
    }
    vb_indent(b, indent + 2);
    vb_str(b, "</InformationKey>\n");
  }
  if (!str && a->units) {
    vb_indent(b, indent + 2);
    vb_str(b, "<InformationKey name=\"UNITS_LABEL\" location=\"vtkDataArray\">\n");
    vb_indent(b, indent + 4);
    vb_attr_text(b, a->units);
    vb_str(b, "\n");
    vb_indent(b, indent + 2);
    vb_str(b, "</InformationKey>\n");
  }
  vb_indent(b, indent);
  vb_printf(b, "</%s>\n", tag);
  return b->failed ? -1 : 0;
}

static void put_data(vbuf_t *b, const char *tag, int n, const karst_i_vtp_array_t *arrays,
                     const char *scalars) {
  vb_indent(b, 6);
  vb_printf(b, "<%s", tag);
  if (scalars) {
    vb_str(b, " Scalars=\"");
    vb_attr_text(b, scalars);
    vb_str(b, "\"");
  }
  vb_str(b, ">\n");
  for (int i = 0; i < n; i++)
    put_array(b, 8, &arrays[i], 0);
  vb_indent(b, 6);
  vb_printf(b, "</%s>\n", tag);
}

static const char *const cell_tags[4] = {"Verts", "Lines", "Strips", "Polys"};

karst_error_t karst_i_vtp_write(karst_ctx_t *ctx, const char *path,
                                const karst_i_vtp_polydata_t *pd) {
  if (karst_interrupted(ctx))
    return karst_set_error(ctx, KARST_EINTERRUPTED, "%s: interrupted before writing", path);
  char *tmp = karst_temp_name(path);
  if (!tmp) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  vbuf_t b = {0};
  b.fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (b.fd < 0) {
    int e = errno;
    free(tmp);
    return karst_set_error(ctx, KARST_EIO, "%s: cannot write: %s", path, strerror(e));
  }
  vb_str(&b, "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" "
             "byte_order=\"LittleEndian\" header_type=\"UInt64\" "
             "compressor=\"vtkZLibDataCompressor\">\n  <PolyData>\n");
  if (pd->n_field > 0) {
    vb_str(&b, "    <FieldData>\n");
    for (int i = 0; i < pd->n_field; i++)
      put_array(&b, 6, &pd->field[i], 1);
    vb_str(&b, "    </FieldData>\n");
  }
  vb_printf(&b,
            "    <Piece NumberOfPoints=\"%" PRId64 "\" NumberOfVerts=\"%" PRId64
            "\" NumberOfLines=\"%" PRId64 "\" NumberOfStrips=\"%" PRId64
            "\" NumberOfPolys=\"%" PRId64 "\">\n",
            (int64_t)pd->n_points, (int64_t)pd->n_cells[0], (int64_t)pd->n_cells[1],
            (int64_t)pd->n_cells[2], (int64_t)pd->n_cells[3]);
  put_data(&b, "PointData", pd->n_point, pd->point, pd->point_scalars);
  put_data(&b, "CellData", pd->n_cell, pd->cell, pd->cell_scalars);
  vb_str(&b, "      <Points>\n");
  karst_i_vtp_array_t pts = {"Points", KARST_I_VTP_FLOAT64, 3, NULL, pd->n_points, pd->xyz, NULL};
  put_array(&b, 8, &pts, 0);
  vb_str(&b, "      </Points>\n");
  for (int k = 0; k < 4; k++) {
    karst_int_t nc = pd->n_cells[k];
    karst_int_t len = nc > 0 ? pd->ends[k][nc - 1] : 0;
    karst_i_vtp_array_t conn = {"connectivity", KARST_I_VTP_INT64, 1, NULL, len, pd->conn[k], NULL};
    karst_i_vtp_array_t ends = {"offsets", KARST_I_VTP_INT64, 1, NULL, nc, pd->ends[k], NULL};
    vb_indent(&b, 6);
    vb_printf(&b, "<%s>\n", cell_tags[k]);
    put_array(&b, 8, &conn, 0);
    put_array(&b, 8, &ends, 0);
    vb_indent(&b, 6);
    vb_printf(&b, "</%s>\n", cell_tags[k]);
  }
  vb_str(&b, "    </Piece>\n  </PolyData>\n</VTKFile>\n");
  vb_flush(&b);
  if (close(b.fd) != 0 && !b.failed) b.failed = 2, b.err = errno;
  free(b.p);
  karst_error_t err;
  if (b.failed == 1)
    err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory for the file's data", path);
  else if (b.failed)
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot write: %s", path, strerror(b.err));
  if (b.failed) {
    remove(tmp);
  } else {
    err = karst_rename_into_place(ctx, tmp, path);
  }
  free(tmp);
  return err;
}
