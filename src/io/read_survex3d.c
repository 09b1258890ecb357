/* Survex .3d reader, format version 8, written natively from Survex's
 * published specification (doc/3dformat.htm, "Survex 3d Format
 * Specification", O. Betts and M. McCombe, last updated 2016-05-17). */
#include "karst/readers.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "survey_internal.h"

/* The file identifier line (spec, "File Header"). */
static const char MAGIC[] = "Survex 3D Image File\n";
/* File-wide flag: the file is an extended elevation, not a 3-D survey. */
#define FFLAG_EXTENDED 0x80
/* LINE flags (item code & 0x1f): leg above ground, duplicate, splay. */
#define LEG_SURFACE 0x01
#define LEG_DUPLICATE 0x02
#define LEG_SPLAY 0x04
/* LINE item code bit: the label is omitted (no change to the label buffer). */
#define LINE_NO_LABEL 0x20
/* LABEL flags (item code & 0x7f): the station is an entrance. */
#define STATION_ENTRANCE 0x04
/* STYLE_NORMAL: when the style is already normal, a 0x00 byte ends the data. */
#define STYLE_NORMAL 0
#define STYLE_UNKNOWN (-1)

typedef struct reader {
  karst_ctx_t *ctx;
  const char *path;
  const unsigned char *b;
  size_t n, pos;
  char *label; /* the current label buffer (prefix-compressed labels modify it) */
  size_t label_len, label_cap;
} reader_t;

/* Every error names the file and the byte offset of the offending item. */
static karst_error_t fail(reader_t *r, size_t at, karst_error_t code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static karst_error_t fail(reader_t *r, size_t at, karst_error_t code, const char *fmt, ...) {
  char msg[KARST_ERRMSG_MAX / 2];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return karst_set_error(r->ctx, code, "%s: byte %zu: %s", r->path, at, msg);
}

static karst_error_t need(reader_t *r, size_t at, size_t k, const char *what) {
  if (r->n - r->pos >= k) return KARST_SUCCESS;
  return fail(r, at, KARST_EPARSE, "truncated file: the %s needs %zu more bytes, %zu left", what, k,
              r->n - r->pos);
}

static uint32_t get_u32(reader_t *r) {
  const unsigned char *p = r->b + r->pos;
  r->pos += 4;
  return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static int32_t get_i32(reader_t *r) {
  return (int32_t)get_u32(r);
}
static int16_t get_i16(reader_t *r) {
  const unsigned char *p = r->b + r->pos;
  r->pos += 2;
  return (int16_t)(uint16_t)((unsigned)p[0] | (unsigned)p[1] << 8);
}

/* <x> <y> <z>: 4-byte little-endian signed centimetres. */
static karst_error_t get_key(reader_t *r, size_t at, const char *what, karst_i_cmkey_t *k) {
  karst_error_t err = need(r, at, 12, what);
  if (err) return err;
  k->x = get_i32(r);
  k->y = get_i32(r);
  k->z = get_i32(r);
  return KARST_SUCCESS;
}

/*
 * <label>: remove the last D bytes of the label buffer, then append the next
 * A bytes of the file. One byte non-zero: D = byte >> 4, A = byte & 15;
 * otherwise D and A each follow as one byte, 255 meaning a 4-byte unsigned
 * value follows (spec, end of "Items").
 */
static karst_error_t get_label(reader_t *r, size_t at, const char *what) {
  karst_error_t err;
  size_t del, add;
  if ((err = need(r, at, 1, what))) return err;
  unsigned c = r->b[r->pos++];
  if (c) {
    del = c >> 4;
    add = c & 0x0f;
  } else {
    if ((err = need(r, at, 1, what))) return err;
    c = r->b[r->pos++];
    if (c == 255) {
      if ((err = need(r, at, 4, what))) return err;
      del = get_u32(r);
    } else
      del = c;
    if ((err = need(r, at, 1, what))) return err;
    c = r->b[r->pos++];
    if (c == 255) {
      if ((err = need(r, at, 4, what))) return err;
      add = get_u32(r);
    } else
      add = c;
  }
  if (del > r->label_len)
    return fail(r, at, KARST_EPARSE,
                "label overrun: the %s removes %zu bytes from a label of %zu bytes", what, del,
                r->label_len);
  if (add > r->n - r->pos)
    return fail(r, at, KARST_EPARSE,
                "label overrun: the %s appends %zu label bytes but only %zu remain in the file",
                what, add, r->n - r->pos);
  r->label_len -= del;
  if (r->label_len + add + 1 > r->label_cap) {
    size_t cap = r->label_cap ? r->label_cap : 256;
    while (cap < r->label_len + add + 1)
      cap *= 2;
    char *l = realloc(r->label, cap);
    if (!l) return fail(r, at, KARST_ENOMEM, "out of memory for a label of %zu bytes", add);
    r->label = l;
    r->label_cap = cap;
  }
  memcpy(r->label + r->label_len, r->b + r->pos, add);
  r->pos += add;
  r->label_len += add;
  r->label[r->label_len] = '\0';
  return KARST_SUCCESS;
}

/* One header line (up to the next linefeed); returns its start and length. */
static karst_error_t header_line(reader_t *r, const char *what, const char **s, size_t *len) {
  const unsigned char *nl = memchr(r->b + r->pos, '\n', r->n - r->pos);
  if (!nl)
    return fail(r, r->pos, KARST_EPARSE, "truncated file: the header ends inside the %s", what);
  *s = (const char *)r->b + r->pos;
  *len = (size_t)(nl - (r->b + r->pos));
  r->pos += *len + 1;
  return KARST_SUCCESS;
}

static char *dup_n(const char *s, size_t n) {
  char *d = malloc(n + 1);
  if (d) {
    memcpy(d, s, n);
    d[n] = '\0';
  }
  return d;
}

/* Header: id line, "v8", title\0cs[\0separator], timestamp, file-wide flags byte. */
static karst_error_t read_header(reader_t *r, karst_network_t *net) {
  karst_error_t err;
  const char *s = NULL;
  size_t len = 0;
  if (r->n < sizeof MAGIC - 1 || memcmp(r->b, MAGIC, sizeof MAGIC - 1) != 0) {
    if (r->n < sizeof MAGIC - 1 && memcmp(r->b, MAGIC, r->n) == 0)
      return fail(r, r->n, KARST_EPARSE, "truncated file: it ends inside the file identifier");
    return fail(r, 0, KARST_EPARSE,
                "not a Survex .3d file: it does not start with \"Survex 3D Image File\"");
  }
  r->pos = sizeof MAGIC - 1;
  size_t at = r->pos;
  if ((err = header_line(r, "format version line", &s, &len))) return err;
  if (len != 2 || memcmp(s, "v8", 2) != 0)
    return fail(r, at, KARST_EUNSUPPORTED,
                "unsupported .3d format version '%.*s': only version 8 (Survex 1.2.7 and later) "
                "is read; run cavern again on the .svx to rewrite it",
                (int)(len > 32 ? 32 : len), s);
  if ((err = header_line(r, "title and coordinate system line", &s, &len))) return err;
  size_t tlen = strnlen(s, len);
  const char *cs = tlen < len ? s + tlen + 1 : NULL;
  size_t cslen = cs ? strnlen(cs, len - tlen - 1) : 0;
  if (!(net->title = dup_n(s, tlen)))
    return fail(r, at, KARST_ENOMEM, "out of memory for the title");
  if (cslen && !(net->crs = dup_n(cs, cslen)))
    return fail(r, at, KARST_ENOMEM, "out of memory for the coordinate system");
  if ((err = header_line(r, "timestamp line", &s, &len))) return err;
  at = r->pos;
  if ((err = need(r, at, 1, "file-wide flags byte"))) return err;
  if (r->b[r->pos++] & FFLAG_EXTENDED)
    return fail(r, at, KARST_EUNSUPPORTED,
                "the file is an extended elevation (file-wide flag 0x80), whose coordinates are "
                "not 3-D positions; read the plan .3d that cavern wrote instead");
  return KARST_SUCCESS;
}

typedef struct counts {
  karst_int_t legs, splay, surface, duplicate, xsect, xsect_unknown;
} counts_t;

/* LRUD: four signed centimetre values, Survex writes omitted ones as -1 (all bits set). */
static double dimension(int32_t cm) {
  return cm < 0 ? NAN : cm / KARST_I_SURVEY_CM_PER_M;
}

static karst_error_t read_items(reader_t *r, karst_i_survey_t *sv, counts_t *c) {
  karst_error_t err;
  int style = STYLE_UNKNOWN, have_pos = 0;
  karst_int_t cur = -1, p;
  karst_i_cmkey_t k;
  for (;;) {
    size_t at = r->pos;
    if (r->pos >= r->n)
      return fail(r, at, KARST_EPARSE, "truncated file: the data ends without its end marker");
    unsigned opt = r->b[r->pos++];
    if (opt <= 0x04) { /* STYLE_* or, when the style is already normal, STOP */
      if (opt == STYLE_NORMAL && style == STYLE_NORMAL) return KARST_SUCCESS;
      style = (int)opt;
    } else if (opt == 0x0f) { /* MOVE <x> <y> <z> */
      if ((err = get_key(r, at, "MOVE item", &k)) || (err = karst_i_survey_point(sv, k, &cur)))
        goto item_error;
      have_pos = 1;
    } else if (opt >= 0x10 && opt <= 0x13) { /* DATE: none, 2, 2+1 or 2+2 bytes */
      static const size_t date_len[4] = {0, 2, 3, 4};
      if ((err = need(r, at, date_len[opt - 0x10], "DATE item"))) return err;
      r->pos += date_len[opt - 0x10];
    } else if (opt == 0x1f) { /* ERROR <legs> <length> <E> <H> <V> */
      if ((err = need(r, at, 20, "ERROR item"))) return err;
      r->pos += 20;
    } else if (opt >= 0x30 && opt <= 0x33) { /* XSECT <label> <L> <R> <U> <D> */
      double lrud[4];
      if ((err = get_label(r, at, "XSECT item"))) return err;
      if ((err = need(r, at, opt < 0x32 ? 8 : 16, "XSECT item"))) return err;
      for (int i = 0; i < 4; i++)
        lrud[i] = dimension(opt < 0x32 ? get_i16(r) : get_i32(r));
      c->xsect++;
      if ((p = karst_i_survey_lookup(sv, r->label)) < 0) {
        /* The spec requires a LABEL first; other writers may not: keep going. */
        c->xsect_unknown++;
        continue;
      }
      double *dst = sv->points[p].lrud;
      if (isnan(dst[0]) && isnan(dst[1]) && isnan(dst[2]) && isnan(dst[3]))
        memcpy(dst, lrud, sizeof lrud);
    } else if (opt >= 0x40 && opt <= 0x7f) { /* LINE [<label>] <x> <y> <z> */
      if (!(opt & LINE_NO_LABEL) && (err = get_label(r, at, "LINE item"))) return err;
      if ((err = get_key(r, at, "LINE item", &k))) return err;
      if (!have_pos)
        return fail(r, at, KARST_EPARSE, "LINE item with no current position (no MOVE before it)");
      if ((err = karst_i_survey_point(sv, k, &p))) goto item_error;
      unsigned flags = opt & 0x1f;
      c->legs++;
      if (flags & LEG_SPLAY)
        c->splay++;
      else if (flags & LEG_SURFACE)
        c->surface++;
      else if (flags & LEG_DUPLICATE)
        c->duplicate++;
      else if ((err = karst_i_survey_leg(sv, cur, p)))
        goto item_error;
      cur = p;
    } else if (opt >= 0x80) { /* LABEL <label> <x> <y> <z>, station flags in opt & 0x7f */
      if ((err = get_label(r, at, "LABEL item"))) return err;
      if ((err = get_key(r, at, "LABEL item", &k))) return err;
      if ((err = karst_i_survey_point(sv, k, &p)) || (err = karst_i_survey_name(sv, p, r->label)))
        goto item_error;
      if (opt & STATION_ENTRANCE) sv->points[p].entrance = 1;
    } else {
      return fail(r, at, KARST_EPARSE, "unknown item code 0x%02x", opt);
    }
  }
item_error:
  return fail(r, r->pos, err, "%s", karst_strerror(err));
}

/**
 * karst_read_survex3d: read a Survex .3d file (format version 8) into a network.
 *
 * Implements Survex's "3d Format Specification" (doc/3dformat.htm). Legs
 * (LINE items) flagged splay, surface or duplicate are dropped (METRICS.md:
 * "removed before anything else"); stations are keyed by their integer
 * centimetre coordinates, so stations equated in the survey become one node,
 * and a leg whose ends fall on one node is dropped; nodes that no kept leg
 * uses are dropped. Node labels are the first LABEL name seen at a point;
 * LRUD from XSECT items become the node attribute "lrud" (L, R, U, D in
 * metres, NAN where absent); stations flagged as entrances give the node attribute "entrance"
 * (1 there, 0 elsewhere); the coordinate-system string goes to net->crs
 * and the title to net->title.
 *
 * @param ctx  context for the error message ("FILE: byte OFFSET: message")
 * @param path the .3d file
 * @param net  initialised network, replaced by the survey on success and left
 *             empty on failure
 * @return KARST_SUCCESS; KARST_EIO (cannot read), KARST_EPARSE (wrong magic,
 *         truncated file, label overrun, unknown item code, LINE before any
 *         MOVE), KARST_EUNSUPPORTED (a format version other than 8, an
 *         extended elevation), KARST_ENOMEM.
 *
 * Time complexity: O(file size + total label bytes) expected (hashing).
 */
karst_error_t karst_read_survex3d(karst_ctx_t *ctx, const char *path, karst_network_t *net) {
  karst_error_t err;
  unsigned char *data = NULL;
  size_t len = 0;
  karst_network_t out;
  karst_i_survey_t sv;
  counts_t c = {0};
  karst_int_t n_zero = 0;
  reader_t r = {.ctx = ctx, .path = path};
  karst_network_init(&out);
  karst_i_survey_init(&sv);
  if ((err = karst_i_read_file(ctx, path, &data, &len))) goto cleanup;
  r.b = data;
  r.n = len;
  if ((err = read_header(&r, &out))) goto cleanup;
  if ((err = read_items(&r, &sv, &c))) goto cleanup;
  char *title = out.title, *crs = out.crs;
  out.title = out.crs = NULL;
  err = karst_i_survey_build(ctx, &sv, 1, &out, &n_zero);
  out.title = title;
  out.crs = crs;
  if (err) goto cleanup;
  if (c.xsect_unknown)
    karst_log(ctx, KARST_LOG_WARNING, "%s: %lld XSECT items name a station no LABEL defined", path,
              (long long)c.xsect_unknown);
  karst_log(ctx, KARST_LOG_INFO,
            "%s: %lld legs, dropped %lld splay, %lld surface, %lld duplicate and %lld of zero "
            "length; %lld nodes, %lld edges",
            path, (long long)c.legs, (long long)c.splay, (long long)c.surface,
            (long long)c.duplicate, (long long)n_zero, (long long)out.n_nodes,
            (long long)out.n_edges);
  karst_network_destroy(net);
  *net = out;
  karst_network_init(&out);
cleanup:
  karst_network_destroy(&out);
  karst_i_survey_destroy(&sv);
  free(r.label);
  free(data);
  return err;
}
