/* GOCAD PLine (.pl) ASCII objects: VRTX/PVRTX vertices, ATOM/PATOM aliases of an
 * earlier vertex (GOCAD repeats a shared vertex in each ILINE part this way),
 * SEG segments between vertex or atom ids, ILINE parts, END.
 * Reference: GOCAD ASCII file formats (Emerson/Paradigm), "PLine"; Karstnet's from_pline. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/input_internal.h"
#include "karst/readers.h"

/* Open-addressing map from a file's vertex/atom id to a node index. */
typedef struct {
  karst_int_t cap, count;
  karst_int_t *key, *val; /* key -1: empty (ids are >= 0 after the check) */
} idmap_t;

static size_t slot_of(karst_int_t key, karst_int_t cap) {
  uint64_t h = (uint64_t)key * 0x9E3779B97F4A7C15ull;
  return (size_t)(h >> 17) & (size_t)(cap - 1);
}

static int idmap_grow(idmap_t *m) {
  karst_int_t ncap = m->cap ? 2 * m->cap : 1024;
  karst_int_t *k = malloc((size_t)ncap * sizeof *k), *v = malloc((size_t)ncap * sizeof *v);
  if (!k || !v) {
    free(k);
    free(v);
    return -1;
  }
  for (karst_int_t i = 0; i < ncap; i++)
    k[i] = -1;
  for (karst_int_t i = 0; i < m->cap; i++)
    if (m->key[i] >= 0) {
      size_t s = slot_of(m->key[i], ncap);
      while (k[s] >= 0)
        s = (s + 1) & (size_t)(ncap - 1);
      k[s] = m->key[i];
      v[s] = m->val[i];
    }
  free(m->key);
  free(m->val);
  m->key = k;
  m->val = v;
  m->cap = ncap;
  return 0;
}

/* Node index of @p key, or -1. */
static karst_int_t idmap_get(const idmap_t *m, karst_int_t key) {
  if (m->cap == 0) return -1;
  for (size_t s = slot_of(key, m->cap);; s = (s + 1) & (size_t)(m->cap - 1)) {
    if (m->key[s] == key) return m->val[s];
    if (m->key[s] < 0) return -1;
  }
}

/* 0, 1 when the key exists already, -1 when out of memory. */
static int idmap_put(idmap_t *m, karst_int_t key, karst_int_t val) {
  if (2 * (m->count + 1) > m->cap && idmap_grow(m)) return -1;
  size_t s = slot_of(key, m->cap);
  while (m->key[s] >= 0) {
    if (m->key[s] == key) return 1;
    s = (s + 1) & (size_t)(m->cap - 1);
  }
  m->key[s] = key;
  m->val[s] = val;
  m->count++;
  return 0;
}

static void idmap_clear(idmap_t *m) {
  for (karst_int_t i = 0; i < m->cap; i++)
    m->key[i] = -1;
  m->count = 0;
}

static int parse_id(const char *s, karst_int_t *out) {
  char *end;
  errno = 0;
  long long v = strtoll(s, &end, 10);
  if (end == s || *end != '\0' || errno || v < 0) return -1;
  *out = (karst_int_t)v;
  return 0;
}

static int parse_coord(const char *s, double *out) {
  char *end;
  double v = strtod(s, &end);
  if (end == s || *end != '\0' || !isfinite(v)) return -1;
  *out = v;
  return 0;
}

enum { MAX_TOKENS = 8 };

/**
 * Read a GOCAD PLine file into @p net: one node per VRTX/PVRTX, ATOM/PATOM
 * ids resolved to the node of the vertex they repeat, one edge per SEG.
 * Ids are per object (reset at each "GOCAD PLine" header), so several objects
 * in one file are read as one network.
 *
 * @param ctx  context (errors as "FILE:LINE: message")
 * @param path the .pl file
 * @param net  initialised network; replaced only on success
 * @return KARST_SUCCESS; KARST_EPARSE for a missing header, a GOCAD object
 *         other than PLine (named with its line), a short or
 *         non-numeric VRTX, a repeated id, an ATOM or SEG naming an unknown id,
 *         or a file without vertices; KARST_EIO, KARST_ENOMEM.
 * Time complexity: O(file size) expected (hashed ids).
 */
karst_error_t karst_read_pline(karst_ctx_t *ctx, const char *path, karst_network_t *net) {
  karst_error_t err = KARST_SUCCESS;
  karst_network_t tmp;
  karst_network_init(&tmp);
  idmap_t ids = {0, 0, NULL, NULL};
  char *line = NULL;
  size_t cap = 0;
  long lineno = 0;
  int seen_header = 0, in_block = 0;
  FILE *fp;
  if ((err = karst_i_open_regular(ctx, path, "GOCAD PLine", KARST_SURVEY_MAX_BYTES, &fp)))
    return err;
  while (getline(&line, &cap, fp) >= 0) {
    lineno++;
    char *tok[MAX_TOKENS];
    int n = 0;
    int last_is_brace = 0;
    char *save = NULL;
    for (char *s = strtok_r(line, " \t\r\n", &save); s; s = strtok_r(NULL, " \t\r\n", &save)) {
      if (n < MAX_TOKENS) tok[n++] = s;
      last_is_brace = strcmp(s, "{") == 0 || (s[0] && s[strlen(s) - 1] == '{');
    }
    if (n == 0) continue;
    if (in_block) { /* HEADER { ... } and PROPERTY_CLASS_HEADER X { ... }: skipped */
      if (strcmp(tok[0], "}") == 0)
        in_block = 0;
      else if (strncmp(tok[0], "name:", 5) == 0 && !tmp.title)
        tmp.title = strdup(tok[0] + 5);
      continue;
    }
    if (last_is_brace) {
      in_block = 1;
      continue;
    }
    /* Another GOCAD object type (TSurf, VSet, SGrid ...) has VRTX lines too: reading them as
     * cave stations would be wrong, so name the type instead of guessing. */
    if (n >= 2 && strcmp(tok[0], "GOCAD") == 0 && strcmp(tok[1], "PLine") != 0) {
      err = karst_set_error(ctx, KARST_EPARSE,
                            "%s:%ld: GOCAD %s object: only GOCAD PLine objects are read", path,
                            lineno, tok[1]);
      goto cleanup;
    }
    if (!seen_header) {
      if (!(n >= 2 && strcmp(tok[0], "GOCAD") == 0)) {
        err = karst_set_error(ctx, KARST_EPARSE,
                              "%s:%ld: not a GOCAD PLine file: expected 'GOCAD PLine', got '%s'",
                              path, lineno, tok[0]);
        goto cleanup;
      }
      seen_header = 1;
      continue;
    }
    if (strcmp(tok[0], "GOCAD") == 0) {
      idmap_clear(&ids); /* a new object: ids start again */
      continue;
    }
    int is_vrtx = strcmp(tok[0], "VRTX") == 0 || strcmp(tok[0], "PVRTX") == 0;
    int is_atom = strcmp(tok[0], "ATOM") == 0 || strcmp(tok[0], "PATOM") == 0;
    int is_seg = strcmp(tok[0], "SEG") == 0;
    if (!is_vrtx && !is_atom && !is_seg) continue; /* ILINE, END, coordinate system, ... */
    int need = is_vrtx ? 5 : 3;
    if (n < need) {
      err = karst_set_error(
          ctx, KARST_EPARSE, "%s:%ld: %s needs %s, got %d value%s", path, lineno, tok[0],
          is_vrtx ? "an id and x y z" : (is_atom ? "an id and a vertex id" : "two vertex ids"),
          n - 1, n == 2 ? "" : "s");
      goto cleanup;
    }
    karst_int_t a, b;
    if (parse_id(tok[1], &a)) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: %s: '%s' is not a vertex id", path, lineno,
                            tok[0], tok[1]);
      goto cleanup;
    }
    if (is_vrtx) {
      double x[3];
      for (int c = 0; c < 3; c++)
        if (parse_coord(tok[2 + c], &x[c])) {
          err = karst_set_error(ctx, KARST_EPARSE,
                                "%s:%ld: %s %lld: coordinate %c: '%s' is not a finite number", path,
                                lineno, tok[0], (long long)a, "xyz"[c], tok[2 + c]);
          goto cleanup;
        }
      karst_int_t idx;
      if (karst_network_add_node(&tmp, x[0], x[1], x[2], &idx)) goto nomem;
      int r = idmap_put(&ids, a, idx);
      if (r < 0) goto nomem;
      if (r > 0) {
        err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: %s %lld: id already used", path, lineno,
                              tok[0], (long long)a);
        goto cleanup;
      }
      continue;
    }
    if (parse_id(tok[2], &b)) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: %s: '%s' is not a vertex id", path, lineno,
                            tok[0], tok[2]);
      goto cleanup;
    }
    karst_int_t nb = idmap_get(&ids, b);
    if (is_atom) {
      if (nb < 0) {
        err = karst_set_error(ctx, KARST_EPARSE,
                              "%s:%ld: %s %lld repeats vertex %lld, which is "
                              "not defined before",
                              path, lineno, tok[0], (long long)a, (long long)b);
        goto cleanup;
      }
      int r = idmap_put(&ids, a, nb);
      if (r < 0) goto nomem;
      if (r > 0) {
        err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: %s %lld: id already used", path, lineno,
                              tok[0], (long long)a);
        goto cleanup;
      }
      continue;
    }
    karst_int_t na = idmap_get(&ids, a);
    if (na < 0 || nb < 0) {
      err = karst_set_error(ctx, KARST_EPARSE, "%s:%ld: SEG %lld %lld: vertex %lld is not defined",
                            path, lineno, (long long)a, (long long)b, (long long)(na < 0 ? a : b));
      goto cleanup;
    }
    if (karst_network_add_edge(&tmp, na, nb, NULL)) goto nomem;
  }
  if (ferror(fp)) {
    err = karst_set_error(ctx, KARST_EIO, "%s:%ld: read error", path, lineno);
    goto cleanup;
  }
  if (!seen_header) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s: empty file: no 'GOCAD PLine' header", path);
    goto cleanup;
  }
  if (tmp.n_nodes == 0) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s: no VRTX vertices", path);
    goto cleanup;
  }
  karst_network_destroy(net);
  *net = tmp;
  karst_network_init(&tmp);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "%s:%ld: out of memory", path, lineno);
cleanup:
  karst_network_destroy(&tmp);
  free(ids.key);
  free(ids.val);
  free(line);
  fclose(fp);
  return err;
}
