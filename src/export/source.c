/* What `karst export` exports: a network and what its run.json or ensemble.json says about it
 * (key points, coordinate system, seed). See include/karst/export.h. */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "ensemble/ensemble_internal.h"
#include "karst/ensemble.h"
#include "karst/export.h"
#include "karst/json.h"
#include "karst/readers.h"
#include "karst/vtk.h"

void karst_export_source_init(karst_export_source_t *s) {
  memset(s, 0, sizeof *s);
  karst_network_init(&s->net);
  s->member = -1;
}

void karst_export_source_destroy(karst_export_source_t *s) {
  karst_network_destroy(&s->net);
  free(s->key_points);
  free(s->crs);
  free(s->crs_where);
  free(s->network_path);
  free(s->provenance_path);
  free(s->scenario);
  free(s->scenario_hash);
  karst_export_source_init(s);
}

static int is_dir(const char *p) {
  struct stat st;
  return stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

static int exists(const char *p) {
  struct stat st;
  return stat(p, &st) == 0;
}

static char *dup_or_null(const char *s) {
  return s ? strdup(s) : NULL;
}

/* "FILE:LINE:COL" of a JSON value, malloc'ed. */
static char *where(const char *file, const karst_json_t *v) {
  size_t n = strlen(file) + 32;
  char *w = malloc(n);
  if (w) snprintf(w, n, "%s:%d:%d", file, v->line, v->col);
  return w;
}

/* The "crs" member of @p root (top level, else in "parameters": run.json writes both, null
 * without a crs): a string, an EPSG number or null. */
static karst_error_t read_crs(karst_ctx_t *ctx, const char *file, const karst_json_t *root,
                              karst_export_source_t *s) {
  const karst_json_t *c = karst_json_get(root, "crs");
  if (!c || c->type == KARST_JSON_NULL)
    c = karst_json_get(karst_json_get(root, "parameters"), "crs");
  if (!c || c->type == KARST_JSON_NULL) return KARST_SUCCESS;
  char buf[32];
  const char *text = NULL;
  if (c->type == KARST_JSON_STRING && c->text[0]) {
    text = c->text;
  } else if (c->type == KARST_JSON_NUMBER && c->number >= 1 && c->number <= INT32_MAX &&
             c->number == floor(c->number)) {
    snprintf(buf, sizeof buf, "EPSG:%" PRId64, (int64_t)c->number);
    text = buf;
  } else {
    return karst_set_error(ctx, KARST_EPARSE,
                           "%s:%d:%d: crs must be a coordinate system (\"EPSG:2154\", WKT or a "
                           "PROJ string), an EPSG code or null",
                           file, c->line, c->col);
  }
  free(s->crs);
  free(s->crs_where);
  s->crs = strdup(text);
  s->crs_where = where(file, c);
  if (!s->crs || !s->crs_where) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  return KARST_SUCCESS;
}

/* parameters.key_points of run.json / ensemble.json: [{"name", "type", "position"}, ...]. */
static karst_error_t read_key_points(karst_ctx_t *ctx, const char *file, const karst_json_t *root,
                                     karst_export_source_t *s) {
  const karst_json_t *kp = karst_json_get(karst_json_get(root, "parameters"), "key_points");
  if (!kp) return KARST_SUCCESS;
  if (kp->type != KARST_JSON_ARRAY)
    return karst_set_error(ctx, KARST_EPARSE, "%s:%d:%d: parameters.key_points must be an array",
                           file, kp->line, kp->col);
  if (kp->n == 0) return KARST_SUCCESS;
  s->key_points = calloc((size_t)kp->n, sizeof *s->key_points);
  if (!s->key_points) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  for (karst_int_t i = 0; i < kp->n; i++) {
    const karst_json_t *e = &kp->items[i];
    const karst_json_t *name = karst_json_get(e, "name"), *type = karst_json_get(e, "type");
    const karst_json_t *pos = karst_json_get(e, "position");
    karst_export_keypoint_t *k = &s->key_points[i];
    if (!name || name->type != KARST_JSON_STRING || !type || type->type != KARST_JSON_STRING ||
        !pos || pos->type != KARST_JSON_ARRAY || pos->n != 3)
      return karst_set_error(ctx, KARST_EPARSE,
                             "%s:%d:%d: key point %" PRId64
                             " needs \"name\", \"type\" and a \"position\" of 3 numbers",
                             file, e->line, e->col, (int64_t)i + 1);
    for (int j = 0; j < 3; j++) {
      if (pos->items[j].type != KARST_JSON_NUMBER || !isfinite(pos->items[j].number))
        return karst_set_error(ctx, KARST_EPARSE,
                               "%s:%d:%d: key point '%s': position[%d] must be a finite number",
                               file, pos->items[j].line, pos->items[j].col, name->text, j);
      k->p[j] = pos->items[j].number;
    }
    if (strcmp(type->text, "sink") == 0)
      k->type = KARST_KEYPOINT_SINK;
    else if (strcmp(type->text, "spring") == 0)
      k->type = KARST_KEYPOINT_SPRING;
    else if (strcmp(type->text, "waypoint") == 0)
      k->type = KARST_KEYPOINT_WAYPOINT;
    else
      return karst_set_error(ctx, KARST_EPARSE,
                             "%s:%d:%d: key point '%s': type must be sink, spring or waypoint, "
                             "got '%s'",
                             file, type->line, type->col, name->text, type->text);
    snprintf(k->name, sizeof k->name, "%s", name->text);
    k->node = -1;
    s->n_key_points++;
  }
  return KARST_SUCCESS;
}

/* Scenario, hash and seed recorded in run.json / ensemble.json. */
static karst_error_t read_provenance(karst_ctx_t *ctx, const char *file, int is_run,
                                     karst_export_source_t *s) {
  karst_json_t *root = NULL;
  karst_error_t err = karst_json_read_file(ctx, file, &root);
  if (err) return err;
  if (root->type != KARST_JSON_OBJECT) {
    err = karst_set_error(ctx, KARST_EPARSE, "%s:%d:%d: expected a JSON object", file, root->line,
                          root->col);
    goto cleanup;
  }
  const karst_json_t *v = karst_json_get(root, "scenario");
  if (v && v->type == KARST_JSON_STRING && !(s->scenario = strdup(v->text))) goto nomem;
  v = karst_json_get(root, "scenario_hash");
  if (v && v->type == KARST_JSON_STRING && !(s->scenario_hash = strdup(v->text))) goto nomem;
  v = karst_json_get(root, "seed");
  if (is_run && v && v->type == KARST_JSON_NUMBER && v->text) {
    /* The literal, not the double: seeds use all 64 bits. */
    char *end;
    errno = 0;
    unsigned long long seed = strtoull(v->text, &end, 10);
    if (!errno && !*end) {
      s->seed = seed;
      s->have_seed = 1;
    }
  }
  if (!(s->provenance_path = strdup(file))) goto nomem;
  if ((err = read_crs(ctx, file, root, s))) goto cleanup;
  err = read_key_points(ctx, file, root, s);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
cleanup:
  karst_json_free(root);
  return err;
}

/* The seed of an ensemble member, from its own metrics.csv (columns index, seed, ...). */
static karst_error_t read_member_seed(karst_ctx_t *ctx, const char *dir, karst_export_source_t *s) {
  char *path = karst_i_path_join(dir, "metrics.csv");
  if (!path) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  karst_error_t err = KARST_SUCCESS;
  if (exists(path)) {
    karst_ensemble_table_t t;
    karst_ensemble_table_init(&t);
    err = karst_ensemble_table_read(ctx, path, &t);
    if (!err && t.n_rows == 1) {
      s->seed = t.seed[0];
      s->have_seed = 1;
      s->member = t.index[0];
    }
    karst_ensemble_table_destroy(&t);
  }
  free(path);
  return err;
}

/* Each key point's node: the network node at exactly its position (the generator inserts key
 * points as samples, so their nodes carry the very coordinates). */
static void match_nodes(karst_export_source_t *s) {
  for (int k = 0; k < s->n_key_points; k++) {
    karst_export_keypoint_t *kp = &s->key_points[k];
    for (karst_int_t i = 0; i < s->net.n_nodes; i++) {
      const double *p = &s->net.xyz[3 * i];
      if (p[0] == kp->p[0] && p[1] == kp->p[1] && p[2] == kp->p[2]) {
        kp->node = i;
        break;
      }
    }
  }
}

/**
 * Load what @p path holds for export (see export.h).
 * @param ctx   context: errors name the file.
 * @param path  a `karst generate` directory, an ensemble member directory, or a network file.
 * @param s     initialised by the caller; filled on success, emptied on failure.
 * @return KARST_SUCCESS, KARST_ENOTFOUND (no network.vtp in the directory), the reader's
 *         errors (KARST_EPARSE, KARST_EIO ...), KARST_ENOMEM.
 * Time complexity: O(nodes x key points + size of the files).
 */
karst_error_t karst_export_source_load(karst_ctx_t *ctx, const char *path,
                                       karst_export_source_t *s) {
  karst_error_t err = KARST_SUCCESS;
  char *run = NULL, *ens = NULL, *key = NULL, *parent = NULL;
  karst_export_source_destroy(s);
  if (!path || !*path) return karst_set_error(ctx, KARST_EINVAL, "no input given");
  if (is_dir(path)) {
    s->network_path = karst_i_path_join(path, "network.vtp");
    run = karst_i_path_join(path, "run.json");
    parent = karst_i_path_join(path, "..");
    ens = parent ? karst_i_path_join(parent, "../ensemble.json") : NULL;
    key = parent ? karst_i_path_join(parent, "ensemble.key") : NULL;
    if (!s->network_path || !run || !ens || !key) goto nomem;
    if (!exists(s->network_path)) {
      err = karst_set_error(ctx, KARST_ENOTFOUND,
                            "%s: no network.vtp in this directory (give a directory written by "
                            "`karst generate`, an ensemble member DIR/realisations/NNNN, or a "
                            "network or survey file)",
                            path);
      goto cleanup;
    }
    if ((err = karst_vtk_read_network(ctx, s->network_path, &s->net))) goto cleanup;
    if (s->net.crs && !(s->crs = strdup(s->net.crs))) goto nomem;
    if (s->net.crs && !(s->crs_where = strdup(s->network_path))) goto nomem;
    if (exists(run)) {
      err = read_provenance(ctx, run, 1, s);
    } else if (exists(key) && exists(ens)) {
      err = read_provenance(ctx, ens, 0, s);
      if (!err) err = read_member_seed(ctx, path, s);
    }
    if (err) goto cleanup;
  } else {
    if (!(s->network_path = strdup(path))) goto nomem;
    if ((err = karst_read_network(ctx, path, KARST_FORMAT_AUTO, &s->net))) goto cleanup;
    if (s->net.crs && (!(s->crs = strdup(s->net.crs)) || !(s->crs_where = dup_or_null(path))))
      goto nomem;
  }
  match_nodes(s);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
cleanup:
  if (err) karst_export_source_destroy(s);
  free(run);
  free(ens);
  free(key);
  free(parent);
  return err;
}
