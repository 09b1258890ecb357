/* Scenario values given in place of the file's (karst_scenario_load_with_overrides), and the
 * scenario file written back with them (karst_scenario_write_with_overrides).
 *
 * Why the overrides go into the YAML document rather than into karst_scenario_t: the schema
 * walk of scenario.c then reads an override exactly as it reads a value of the file, so the
 * same type and range checks, cross-field rules and "did you mean" hints apply, and no second
 * table of keys can drift from the parser's. Nodes added by overrides are recognised by their
 * document id (every node added after the file's own), so messages about them name the
 * override ("--vary skeleton.gama=0.5:3: unknown key 'gama' in skeleton (did you mean
 * 'gamma'?)") instead of a file position. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/io.h"
#include "scenario_internal.h"

/* ------------------------------------------------------------------------ */
/* The set                                                                  */
/* ------------------------------------------------------------------------ */

karst_error_t karst_i_overrides_init(karst_ctx_t *ctx, karst_i_override_set_t *set,
                                     const karst_scenario_override_t *ov, int n) {
  memset(set, 0, sizeof *set);
  if (n < 0 || (n > 0 && !ov))
    return karst_set_error(ctx, KARST_EINVAL, "invalid override list (%d entries)", n);
  for (int k = 0; k < n; k++)
    for (int j = 0; j < k; j++)
      if (ov[k].key && ov[j].key && !strcmp(ov[k].key, ov[j].key))
        return karst_set_error(ctx, KARST_EINVAL, "the key %.*s is overridden twice",
                               KARST_SCENARIO_OVERRIDE_KEY_MAX, ov[k].key);
  set->n = n;
  set->ov = ov;
  size_t m = n > 0 ? (size_t)n : 1;
  set->types = calloc(m, sizeof *set->types);
  set->targets = calloc(m, sizeof *set->targets);
  if (!set->types || !set->targets) {
    karst_i_overrides_destroy(set);
    return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  }
  return KARST_SUCCESS;
}

void karst_i_overrides_destroy(karst_i_override_set_t *set) {
  for (int i = 0; i < set->n_files; i++) {
    free(set->file_keys[i]);
    free(set->file_values[i]);
  }
  free(set->file_keys);
  free(set->file_values);
  free(set->types);
  free(set->targets);
  free(set->owner);
  memset(set, 0, sizeof *set);
}

int karst_i_overrides_note_file(karst_i_override_set_t *set, const char *key, const char *value) {
  if (set->n_files == set->cap_files) {
    int cap = set->cap_files ? 2 * set->cap_files : 8;
    char **k = realloc(set->file_keys, (size_t)cap * sizeof *k);
    if (!k) return -1;
    set->file_keys = k;
    char **v = realloc(set->file_values, (size_t)cap * sizeof *v);
    if (!v) return -1;
    set->file_values = v;
    set->cap_files = cap;
  }
  char *kc = strdup(key), *vc = strdup(value);
  if (!kc || !vc) {
    free(kc);
    free(vc);
    return -1;
  }
  set->file_keys[set->n_files] = kc;
  set->file_values[set->n_files] = vc;
  set->n_files++;
  return 0;
}

int karst_i_override_of(const karst_i_override_set_t *set, const yaml_document_t *doc,
                        const yaml_node_t *n) {
  if (!set || set->first_node <= 0 || !n) return -1;
  long id = (long)(n - doc->nodes.start) + 1;
  long k = id - set->first_node;
  if (k < 0 || k >= set->n_added) return -1;
  return set->owner[k];
}

const char *karst_i_override_label(const karst_i_override_set_t *set, int k, char *buf,
                                   size_t size) {
  const karst_scenario_override_t *o = &set->ov[k];
  if (o->origin) return o->origin;
  snprintf(buf, size, "override %.*s=%.*s", KARST_SCENARIO_OVERRIDE_KEY_MAX, o->key ? o->key : "",
           64, o->value ? o->value : "");
  return buf;
}

/* ------------------------------------------------------------------------ */
/* Key paths: name ('[' index ']')* ('.' name ('[' index ']')*)*             */
/* ------------------------------------------------------------------------ */

typedef struct step {
  const char *name; /* a map key (not NUL-terminated), or NULL for a list index */
  size_t len;
  long index;
  int end; /* length of the key's text up to and including this step */
} step_t;

/* Longest path: every step is at least one character and a separator. */
#define MAX_STEPS (KARST_SCENARIO_OVERRIDE_KEY_MAX / 2 + 1)

static int name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

/* Split @p key into steps; returns the count, or -1 with a reason in @p why. */
static int parse_path(const char *key, step_t *steps, const char **why) {
  int n = 0;
  const char *p = key;
  if (!key || !*key) {
    *why = "the key is empty";
    return -1;
  }
  if (strlen(key) > KARST_SCENARIO_OVERRIDE_KEY_MAX) {
    *why = "the key is longer than 255 characters";
    return -1;
  }
  for (;;) {
    const char *s = p;
    while (name_char(*p))
      p++;
    if (p == s) {
      *why = "each part of the key must be a name of letters, digits and '_' (e.g. "
             "skeleton.gamma, fractures[0].weight)";
      return -1;
    }
    steps[n++] = (step_t){s, (size_t)(p - s), 0, (int)(p - key)};
    while (*p == '[') {
      char *end;
      p++;
      if (*p < '0' || *p > '9') {
        *why = "a list index must be a whole number in brackets, e.g. fractures[0]";
        return -1;
      }
      errno = 0;
      long i = strtol(p, &end, 10);
      if (errno || *end != ']' || i > INT_MAX) {
        *why = "a list index must be a whole number in brackets, e.g. fractures[0]";
        return -1;
      }
      p = end + 1;
      steps[n++] = (step_t){NULL, 0, i, (int)(p - key)};
    }
    if (*p == '\0') return n;
    if (*p != '.') {
      *why = "parts of the key are joined by '.', list indices written [i]";
      return -1;
    }
    p++;
  }
}

/* ------------------------------------------------------------------------ */
/* Applying                                                                 */
/* ------------------------------------------------------------------------ */

static const char *kind_of(const yaml_node_t *n) {
  switch (n->type) {
  case YAML_MAPPING_NODE:
    return "a map";
  case YAML_SEQUENCE_NODE:
    return "a list";
  default:
    return "a single value";
  }
}

/* Record that node @p id was added by override @p k. */
static int note_added(karst_i_override_set_t *set, int id, int k) {
  int slot = id - set->first_node;
  if (slot < 0) return -1;
  if (slot >= set->cap_added) {
    int cap = set->cap_added ? set->cap_added : 16;
    while (cap <= slot)
      cap *= 2;
    int *o = realloc(set->owner, (size_t)cap * sizeof *o);
    if (!o) return -1;
    set->owner = o;
    set->cap_added = cap;
  }
  for (int i = set->n_added; i < slot; i++)
    set->owner[i] = k;
  set->owner[slot] = k;
  if (slot + 1 > set->n_added) set->n_added = slot + 1;
  return 0;
}

static int add_scalar(yaml_document_t *doc, karst_i_override_set_t *set, int k, const char *s,
                      size_t len) {
  int id = yaml_document_add_scalar(doc, NULL, (yaml_char_t *)s, (int)len, YAML_PLAIN_SCALAR_STYLE);
  if (id && note_added(set, id, k)) return 0;
  return id;
}

/* How many times node @p id is referenced as a value or item of @p doc (an alias makes it
 * more than once). O(document size). */
static int references(const yaml_document_t *doc, int id) {
  int refs = 0;
  for (yaml_node_t *n = doc->nodes.start; n < doc->nodes.top; n++) {
    if (n->type == YAML_MAPPING_NODE) {
      for (yaml_node_pair_t *p = n->data.mapping.pairs.start; p < n->data.mapping.pairs.top; p++)
        refs += (p->value == id) + (p->key == id);
    } else if (n->type == YAML_SEQUENCE_NODE) {
      for (yaml_node_item_t *it = n->data.sequence.items.start; it < n->data.sequence.items.top;
           it++)
        refs += *it == id;
    }
  }
  return refs;
}

/* The pair of map @p map_id whose key is the scalar @p name, or NULL. */
static yaml_node_pair_t *find_pair(yaml_document_t *doc, int map_id, const char *name, size_t len) {
  yaml_node_t *map = yaml_document_get_node(doc, map_id);
  for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top; p++) {
    yaml_node_t *key = yaml_document_get_node(doc, p->key);
    if (key && key->type == YAML_SCALAR_NODE && key->data.scalar.length == len &&
        !memcmp(key->data.scalar.value, name, len))
      return p;
  }
  return NULL;
}

static karst_error_t apply_one(karst_ctx_t *ctx, const char *file, yaml_document_t *doc,
                               karst_i_override_set_t *set, int k) {
  const karst_scenario_override_t *o = &set->ov[k];
  step_t steps[MAX_STEPS];
  char lbl[400];
  const char *label = karst_i_override_label(set, k, lbl, sizeof lbl);
  const char *why = NULL;
  int n = parse_path(o->key, steps, &why);
  if (n < 0) return karst_set_error(ctx, KARST_EINVAL, "%s: %s: %s", file, label, why);
  if (!o->value) return karst_set_error(ctx, KARST_EINVAL, "%s: %s: no value given", file, label);
  const char *key = o->key;
  size_t vlen = strlen(o->value);
  int cur = 1; /* the root map */
  for (int s = 0; s < n; s++) {
    const step_t *st = &steps[s];
    int last = s == n - 1;
    /* The key's text up to this step and up to the one before, for messages. */
    int shown = st->end, before = s > 0 ? steps[s - 1].end : 0;
    yaml_node_t *node = yaml_document_get_node(doc, cur);
    if (st->name) {
      if (node->type != YAML_MAPPING_NODE) {
        return karst_set_error(
            ctx, KARST_EINVAL, "%s: %s: %.*s is %s (line %d), not a map: there is no key %.*s",
            file, label, before, key, kind_of(node), (int)node->start_mark.line + 1, shown, key);
      }
      yaml_node_pair_t *pair = find_pair(doc, cur, st->name, st->len);
      if (pair) {
        if (last) {
          yaml_node_t *old = yaml_document_get_node(doc, pair->value);
          int old_id = pair->value;
          karst_i_override_target_t *t = &set->targets[k];
          t->replaced = old->type == YAML_SCALAR_NODE;
          t->start = old->start_mark.index;
          t->end = old->end_mark.index;
          t->shared = references(doc, old_id) > 1;
          int id = add_scalar(doc, set, k, o->value, vlen);
          if (!id) goto no_memory;
          /* find the pair again: adding a node may have moved the node array */
          find_pair(doc, cur, st->name, st->len)->value = id;
          return KARST_SUCCESS;
        }
        cur = pair->value;
        continue;
      }
      /* A key the file does not give: add it (a value, or a map leading on). */
      int kid = add_scalar(doc, set, k, st->name, st->len);
      if (!kid) goto no_memory;
      int vid;
      if (last) {
        vid = add_scalar(doc, set, k, o->value, vlen);
      } else if (!steps[s + 1].name) {
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: %s: %.*s is not in the scenario file, so it has no item [%ld]",
                               file, label, shown, key, steps[s + 1].index);
      } else {
        vid = yaml_document_add_mapping(doc, NULL, YAML_BLOCK_MAPPING_STYLE);
        if (vid && note_added(set, vid, k)) vid = 0;
      }
      if (!vid || !yaml_document_append_mapping_pair(doc, cur, kid, vid)) goto no_memory;
      set->targets[k].replaced = 0;
      cur = vid;
      continue;
    }
    /* A list index. */
    long count = node->type == YAML_SEQUENCE_NODE
                     ? (long)(node->data.sequence.items.top - node->data.sequence.items.start)
                     : 0;
    if (node->type != YAML_SEQUENCE_NODE || st->index >= count) {
      if (node->type != YAML_SEQUENCE_NODE)
        return karst_set_error(ctx, KARST_EINVAL, "%s: %s: %.*s is %s (line %d), not a list", file,
                               label, before, key, kind_of(node), (int)node->start_mark.line + 1);
      return karst_set_error(ctx, KARST_ERANGE,
                             "%s: %s: %.*s has %ld item%s (indices from 0), so there is no %.*s",
                             file, label, before, key, count, count == 1 ? "" : "s", shown, key);
    }
    int item = node->data.sequence.items.start[st->index];
    if (last) {
      yaml_node_t *old = yaml_document_get_node(doc, item);
      karst_i_override_target_t *t = &set->targets[k];
      t->replaced = old->type == YAML_SCALAR_NODE;
      t->start = old->start_mark.index;
      t->end = old->end_mark.index;
      t->shared = references(doc, item) > 1;
      int id = add_scalar(doc, set, k, o->value, vlen);
      if (!id) goto no_memory;
      node = yaml_document_get_node(doc, cur);
      node->data.sequence.items.start[st->index] = id;
      return KARST_SUCCESS;
    }
    cur = item;
  }
  return KARST_SUCCESS;
no_memory:
  return karst_set_error(ctx, KARST_ENOMEM, "%s: %s: out of memory", file, label);
}

/**
 * Put the overrides of @p set into @p doc (see scenario_internal.h), in order (a key is
 * overridden at most once: karst_i_overrides_init refuses a repeated key).
 * Time complexity: O(n × document size).
 */
karst_error_t karst_i_overrides_apply(karst_ctx_t *ctx, const char *file, yaml_document_t *doc,
                                      karst_i_override_set_t *set) {
  yaml_node_t *root = yaml_document_get_root_node(doc);
  if (!root || root->type != YAML_MAPPING_NODE)
    return karst_set_error(ctx, KARST_EINVAL, "%s: overrides need a scenario that is a map", file);
  if (set->first_node == 0) set->first_node = (int)(doc->nodes.top - doc->nodes.start) + 1;
  for (int k = 0; k < set->n; k++) {
    karst_error_t err = apply_one(ctx, file, doc, set, k);
    if (err) return err;
  }
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Public API                                                               */
/* ------------------------------------------------------------------------ */

/**
 * Read and validate the scenario @p path with @p n values overridden (scenario.h).
 * @param ctx   context; messages about an override name its origin instead of a file position
 * @param path  scenario file
 * @param ov    the overrides, each key at most once
 * @param n     their count (0: karst_scenario_load)
 * @param types NULL or @p n entries: what each override was read as (also on failure, as far
 *              as the walk got, so a caller can tell an integer key given 2.5)
 * @param sc    initialised scenario; replaced on success, untouched on failure
 * @return the codes of karst_scenario_load; KARST_EINVAL also for a malformed key path, a path
 *         through a value that is not a map or a list, and a numeric override of a key that
 *         holds no number; KARST_ERANGE for a list index beyond the list.
 * Time complexity: O(file size × (1 + n)) plus that of karst_scenario_load.
 */
karst_error_t karst_scenario_load_with_overrides(karst_ctx_t *ctx, const char *path,
                                                 const karst_scenario_override_t *ov, int n,
                                                 karst_override_type_t *types,
                                                 karst_scenario_t *sc) {
  karst_i_override_set_t set;
  karst_error_t err = karst_i_overrides_init(ctx, &set, ov, n);
  if (err) return err;
  err = karst_i_scenario_load(ctx, path, &set, sc, NULL, NULL, NULL);
  if (types) memcpy(types, set.types, (size_t)n * sizeof *types); /* also on failure */
  karst_i_overrides_destroy(&set);
  return err;
}

/* The node at key path @p key of @p doc (maps by key, lists by index), or NULL when the file
 * does not give it; -1 for a malformed path. */
static int lookup(yaml_document_t *doc, const char *key, yaml_node_t **out) {
  step_t steps[MAX_STEPS];
  const char *why;
  int n = parse_path(key, steps, &why);
  *out = NULL;
  if (n < 0) return -1;
  yaml_node_t *root = yaml_document_get_root_node(doc);
  int cur = root ? (int)(root - doc->nodes.start) + 1 : 0;
  for (int s = 0; s < n && cur; s++) {
    yaml_node_t *node = yaml_document_get_node(doc, cur);
    if (steps[s].name) {
      yaml_node_pair_t *p =
          node->type == YAML_MAPPING_NODE ? find_pair(doc, cur, steps[s].name, steps[s].len) : NULL;
      cur = p ? p->value : 0;
    } else {
      long count = node->type == YAML_SEQUENCE_NODE
                       ? (long)(node->data.sequence.items.top - node->data.sequence.items.start)
                       : 0;
      cur = steps[s].index < count ? node->data.sequence.items.start[steps[s].index] : 0;
    }
  }
  *out = cur ? yaml_document_get_node(doc, cur) : NULL;
  return 0;
}

/**
 * The text of the value that scenario @p path gives at key path @p key (scenario.h), e.g.
 * "0.1" for tortuosity. The scenario is read and validated first.
 * @return KARST_SUCCESS with the text in @p out; KARST_ENOTFOUND when the file does not give
 *         the key (the default applies) or gives a map or a list there; KARST_EINVAL for a
 *         malformed key path; the codes of karst_scenario_load.
 * Time complexity: that of karst_scenario_load plus O(file size).
 */
karst_error_t karst_scenario_value_text(karst_ctx_t *ctx, const char *path, const char *key,
                                        char *out, size_t size) {
  karst_scenario_t sc;
  yaml_document_t doc;
  unsigned char *text = NULL;
  size_t len = 0;
  karst_scenario_init(&sc);
  if (size) out[0] = '\0';
  karst_error_t err = karst_i_scenario_load(ctx, path, NULL, &sc, &doc, &text, &len);
  karst_scenario_destroy(&sc);
  if (err) return err;
  yaml_node_t *n = NULL;
  if (lookup(&doc, key, &n) < 0)
    err = karst_set_error(ctx, KARST_EINVAL, "'%s' is not a key path (e.g. skeleton.gamma)", key);
  else if (!n || n->type != YAML_SCALAR_NODE)
    err = karst_set_error(ctx, KARST_ENOTFOUND, "%s gives no value at %s", path, key);
  else
    snprintf(out, size, "%s", (const char *)n->data.scalar.value);
  yaml_document_delete(&doc);
  free(text);
  return err;
}

/* @p target as a path relative to the directory @p from (both absolute and canonical). */
static char *relative_path(const char *from, const char *target) {
  size_t common = 0, i = 0;
  for (; from[i] && target[i] && from[i] == target[i]; i++)
    if (from[i] == '/') common = i;
  if (!from[i] && (target[i] == '/' || !target[i])) common = i;
  int ups = 0;
  if (from[common])
    for (const char *p = from + common; *p; p++)
      ups += *p == '/';
  const char *rest = target + common + (target[common] == '/');
  size_t len = (size_t)ups * 3 + strlen(rest) + 2;
  char *out = malloc(len);
  if (!out) return NULL;
  out[0] = '\0';
  for (int u = 0; u < ups; u++)
    strcat(out, "../");
  strcat(out, rest);
  return out;
}

/* A YAML double-quoted scalar of @p s (\" and \\ escaped; control characters cannot occur in
 * a path the reader accepted). */
static void quote_yaml(FILE *fp, const char *s) {
  fputc('"', fp);
  for (; *s; s++) {
    if (*s == '"' || *s == '\\') fputc('\\', fp);
    fputc(*s, fp);
  }
  fputc('"', fp);
}

/* Byte offset in the UTF-8 @p text of character @p index as libyaml counts marks (characters,
 * after a byte-order mark it skips); -1 beyond the end. O(index). */
static long char_to_byte(const unsigned char *text, size_t len, size_t index) {
  size_t b = (len >= 3 && text[0] == 0xEF && text[1] == 0xBB && text[2] == 0xBF) ? 3 : 0;
  for (size_t c = 0; c < index; c++) {
    if (b >= len) return -1;
    b++;
    while (b < len && (text[b] & 0xC0) == 0x80)
      b++;
  }
  return (long)b;
}

static int cmp_target(const void *a, const void *b) {
  const karst_i_override_target_t *x = *(const karst_i_override_target_t *const *)a;
  const karst_i_override_target_t *y = *(const karst_i_override_target_t *const *)b;
  return x->start < y->start ? -1 : x->start > y->start;
}

static int write_yaml(void *data, unsigned char *buffer, size_t size) {
  return fwrite(buffer, 1, size, (FILE *)data) == size;
}

/* The directory part of @p path ("." when there is none), malloc'ed. */
static char *dir_of(const char *path) {
  const char *slash = strrchr(path, '/');
  if (!slash) return strdup(".");
  size_t len = slash == path ? 1 : (size_t)(slash - path);
  return strndup(path, len);
}

/**
 * Write scenario @p path with @p n overrides applied to @p out (scenario.h): the file's text
 * with the overridden scalars replaced when every override replaces a scalar the file gives
 * (not one shared through an alias), else the document as libyaml emits it. Every relative file
 * path the reader resolved (terrain.heightfield, terrain.surface, surfaces of horizons and
 * strata ...) is rewritten relative to @p out's directory. The file is loaded back
 * (karst_scenario_load) before it replaces @p out.
 * @return the codes of karst_scenario_load_with_overrides for @p path, KARST_EIO when @p out
 *         cannot be written or a file cannot be resolved, KARST_EEXTERNAL when libyaml cannot
 *         emit the document.
 * Time complexity: O(file size × (1 + n + files)) plus two scenario loads.
 */
karst_error_t karst_scenario_write_with_overrides(karst_ctx_t *ctx, const char *path,
                                                  const karst_scenario_override_t *ov, int n,
                                                  const char *header, const char *out) {
  karst_error_t err = KARST_SUCCESS;
  karst_i_override_set_t set, fset;
  karst_scenario_t sc, check;
  yaml_document_t doc;
  int have_doc = 0, n_rebase = 0;
  unsigned char *text = NULL;
  size_t text_len = 0;
  char *src_dir = NULL, *out_dir = NULL, *out_parent = NULL;
  char **rebased = NULL;
  karst_scenario_override_t *fov = NULL;
  const karst_i_override_target_t **order = NULL;
  const char **order_text = NULL;
  karst_atomic_file_t f = {0};
  memset(&fset, 0, sizeof fset);
  karst_scenario_init(&sc);
  karst_scenario_init(&check);
  err = karst_i_overrides_init(ctx, &set, ov, n);
  if (err) return err;
  err = karst_i_scenario_load(ctx, path, &set, &sc, &doc, &text, &text_len);
  if (err) goto cleanup;
  have_doc = 1;

  /* Relative files resolve from the scenario's directory: rewrite them for out's. */
  src_dir = dir_of(path);
  out_parent = dir_of(out);
  fov = calloc((size_t)(set.n_files > 0 ? set.n_files : 1), sizeof *fov);
  rebased = calloc((size_t)(set.n_files > 0 ? set.n_files : 1), sizeof *rebased);
  if (!src_dir || !out_parent || !fov || !rebased) goto no_memory;
  for (int i = 0; i < set.n_files; i++) {
    const char *name = set.file_values[i];
    if (name[0] == '/') continue;
    if (!out_dir && !(out_dir = realpath(out_parent, NULL))) {
      err = karst_set_error(ctx, KARST_EIO, "%s: cannot resolve the directory %s: %s", out,
                            out_parent, strerror(errno));
      goto cleanup;
    }
    size_t len = strlen(src_dir) + strlen(name) + 2;
    char *joined = malloc(len);
    if (!joined) goto no_memory;
    snprintf(joined, len, "%s/%s", src_dir, name);
    char *abs = realpath(joined, NULL);
    free(joined);
    if (!abs) {
      err = karst_set_error(ctx, KARST_EIO, "%s: cannot resolve %s (%s): %s", path, name,
                            set.file_keys[i], strerror(errno));
      goto cleanup;
    }
    rebased[n_rebase] = relative_path(out_dir, abs);
    free(abs);
    if (!rebased[n_rebase]) goto no_memory;
    fov[n_rebase] =
        (karst_scenario_override_t){set.file_keys[i], rebased[n_rebase], "rebasing a file path", 0};
    n_rebase++;
  }
  if (n_rebase > 0) {
    err = karst_i_overrides_init(ctx, &fset, fov, n_rebase);
    if (err) goto cleanup;
    err = karst_i_overrides_apply(ctx, path, &doc, &fset);
    if (err) goto cleanup;
  }

  /* libyaml also reads UTF-16 files; their text is not edited in place. */
  int substitute = !(text_len >= 2 && ((text[0] == 0xFF && text[1] == 0xFE) ||
                                       (text[0] == 0xFE && text[1] == 0xFF)));
  int total = n + n_rebase;
  order = calloc((size_t)(total > 0 ? total : 1), sizeof *order);
  order_text = calloc((size_t)(total > 0 ? total : 1), sizeof *order_text);
  if (!order || !order_text) goto no_memory;
  for (int k = 0; k < n; k++) {
    if (!set.targets[k].replaced || set.targets[k].shared) substitute = 0;
    order[k] = &set.targets[k];
  }
  for (int k = 0; k < n_rebase; k++) {
    if (!fset.targets[k].replaced || fset.targets[k].shared) substitute = 0;
    order[n + k] = &fset.targets[k];
  }
  /* Marks count characters: turn them into byte offsets of the UTF-8 text. */
  for (int k = 0; k < total && substitute; k++) {
    karst_i_override_target_t *t = (karst_i_override_target_t *)order[k];
    long a = char_to_byte(text, text_len, t->start), b = char_to_byte(text, text_len, t->end);
    if (a < 0 || b < a) substitute = 0;
    t->start = (size_t)a;
    t->end = (size_t)b;
  }
  qsort(order, (size_t)total, sizeof *order, cmp_target);
  for (int k = 1; k < total; k++)
    if (order[k]->start < order[k - 1]->end) substitute = 0;
  /* The text of each target: a number as given, a path quoted. */
  for (int k = 0; k < total; k++) {
    for (int j = 0; j < n; j++)
      if (order[k] == &set.targets[j]) order_text[k] = ov[j].value;
    for (int j = 0; j < n_rebase; j++)
      if (order[k] == &fset.targets[j]) order_text[k] = NULL; /* quoted below */
  }

  err = karst_atomic_open(ctx, &f, out, "wb");
  if (err) goto cleanup;
  if (header) fputs(header, f.fp);
  if (substitute) {
    size_t at = 0;
    for (int k = 0; k < total; k++) {
      fwrite(text + at, 1, order[k]->start - at, f.fp);
      if (order_text[k]) {
        fputs(order_text[k], f.fp);
      } else {
        for (int j = 0; j < n_rebase; j++)
          if (order[k] == &fset.targets[j]) quote_yaml(f.fp, rebased[j]);
      }
      at = order[k]->end;
    }
    fwrite(text + at, 1, text_len - at, f.fp);
  } else {
    yaml_emitter_t em;
    if (!yaml_emitter_initialize(&em)) goto no_memory;
    yaml_emitter_set_output(&em, write_yaml, f.fp);
    yaml_emitter_set_unicode(&em, 1);
    yaml_emitter_set_width(&em, 100);
    fputs("# Written by karst from the YAML document (the original comments are not kept).\n",
          f.fp);
    int ok = yaml_emitter_open(&em) && yaml_emitter_dump(&em, &doc) && yaml_emitter_close(&em) &&
             yaml_emitter_flush(&em);
    have_doc = 0; /* yaml_emitter_dump deletes the document */
    yaml_emitter_delete(&em);
    if (!ok) {
      err = karst_set_error(ctx, KARST_EEXTERNAL, "%s: libyaml could not write the scenario", out);
      goto cleanup;
    }
  }
  if (ferror(f.fp)) {
    err = karst_set_error(ctx, KARST_EIO, "%s: write error: %s", out, strerror(errno));
    goto cleanup;
  }
  /* Load the temporary back (messages name it; the caller's output stays untouched). */
  fflush(f.fp);
  err = karst_scenario_load(ctx, f.tmp_path, &check);
  if (err) {
    char msg[KARST_ERRMSG_MAX];
    snprintf(msg, sizeof msg, "%s", ctx->errmsg);
    err = karst_set_error(ctx, err, "%s: the written scenario does not load back: %s", out, msg);
    goto cleanup;
  }
  err = karst_atomic_commit(ctx, &f);
  goto cleanup;

no_memory:
  err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", out);
cleanup:
  if (f.fp) karst_atomic_abort(&f);
  if (have_doc) yaml_document_delete(&doc);
  free(text);
  free(order);
  free(order_text);
  for (int k = 0; rebased && k < n_rebase; k++)
    free(rebased[k]);
  free(rebased);
  free(fov);
  free(src_dir);
  free(out_dir);
  free(out_parent);
  karst_scenario_destroy(&sc);
  karst_scenario_destroy(&check);
  karst_i_overrides_destroy(&fset);
  karst_i_overrides_destroy(&set);
  return err;
}

/**
 * The files scenario @p path reads (scenario.h): the walk's resolved file keys, each joined to
 * the scenario's directory when relative.
 * Time complexity: that of karst_scenario_load.
 */
karst_error_t karst_scenario_files(karst_ctx_t *ctx, const char *path, char ***files, int *n) {
  karst_i_override_set_t set;
  karst_scenario_t sc;
  *files = NULL;
  *n = 0;
  karst_error_t err = karst_i_overrides_init(ctx, &set, NULL, 0);
  if (err) return err;
  karst_scenario_init(&sc);
  err = karst_i_scenario_load(ctx, path, &set, &sc, NULL, NULL, NULL);
  karst_scenario_destroy(&sc);
  char *dir = err ? NULL : dir_of(path);
  char **v = err ? NULL : calloc((size_t)set.n_files + 1, sizeof *v);
  if (!err && (!dir || !v)) err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  for (int i = 0; !err && i < set.n_files; i++) {
    const char *name = set.file_values[i];
    size_t len = strlen(dir) + strlen(name) + 2;
    if (!(v[i] = malloc(len))) {
      err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
      break;
    }
    if (name[0] == '/')
      snprintf(v[i], len, "%s", name);
    else
      snprintf(v[i], len, "%s/%s", dir, name);
  }
  if (err) {
    for (int i = 0; v && i < set.n_files; i++)
      free(v[i]);
    free(v);
  } else {
    *files = v;
    *n = set.n_files;
  }
  free(dir);
  karst_i_overrides_destroy(&set);
  return err;
}
