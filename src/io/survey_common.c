/* Station keying by centimetre coordinates and network building shared by
 * the survey readers (src/io/survey_internal.h). */
#include "survey_internal.h"

#include "io/input_internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Tables are kept at most half full so that linear probing stays short. */
#define MAX_LOAD_NUM 1
#define MAX_LOAD_DEN 2

void karst_i_survey_init(karst_i_survey_t *s) {
  memset(s, 0, sizeof *s);
}

void karst_i_survey_destroy(karst_i_survey_t *s) {
  free(s->points);
  free(s->slots);
  free(s->legs);
  if (s->lab_names)
    for (karst_int_t i = 0; i < s->n_lab_slots; i++)
      free(s->lab_names[i]);
  free(s->lab_names);
  free(s->lab_point);
  memset(s, 0, sizeof *s);
}

/* SplitMix64 finaliser: a well-mixed hash of the three coordinates. */
static uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

static uint64_t key_hash(karst_i_cmkey_t k) {
  return mix64((uint64_t)k.x ^ mix64((uint64_t)k.y ^ mix64((uint64_t)k.z)));
}

/* FNV-1a over the bytes of a label. */
static uint64_t str_hash(const char *s) {
  uint64_t h = 1469598103934665603ULL;
  for (; *s; s++)
    h = (h ^ (unsigned char)*s) * 1099511628211ULL;
  return h;
}

static int key_equal(karst_i_cmkey_t a, karst_i_cmkey_t b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

static karst_error_t rehash_points(karst_i_survey_t *s, karst_int_t n_slots) {
  karst_int_t *slots = calloc((size_t)n_slots, sizeof *slots);
  if (!slots) return KARST_ENOMEM;
  for (karst_int_t i = 0; i < s->n_points; i++) {
    uint64_t h = key_hash(s->points[i].key) & (uint64_t)(n_slots - 1);
    while (slots[h])
      h = (h + 1) & (uint64_t)(n_slots - 1);
    slots[h] = i + 1;
  }
  free(s->slots);
  s->slots = slots;
  s->n_slots = n_slots;
  return KARST_SUCCESS;
}

karst_error_t karst_i_survey_point(karst_i_survey_t *s, karst_i_cmkey_t key, karst_int_t *index) {
  karst_error_t err;
  if ((s->n_points + 1) * MAX_LOAD_DEN > s->n_slots * MAX_LOAD_NUM &&
      (err = rehash_points(s, s->n_slots ? 2 * s->n_slots : 64)))
    return err;
  uint64_t mask = (uint64_t)(s->n_slots - 1), h = key_hash(key) & mask;
  for (; s->slots[h]; h = (h + 1) & mask)
    if (key_equal(s->points[s->slots[h] - 1].key, key)) {
      *index = s->slots[h] - 1;
      return KARST_SUCCESS;
    }
  if (s->n_points == s->cap_points) {
    karst_int_t cap = s->cap_points ? 2 * s->cap_points : 64;
    karst_i_survey_point_t *p = realloc(s->points, (size_t)cap * sizeof *p);
    if (!p) return KARST_ENOMEM;
    s->points = p;
    s->cap_points = cap;
  }
  karst_i_survey_point_t *p = &s->points[s->n_points];
  p->key = key;
  p->label = NULL;
  p->entrance = 0;
  for (int c = 0; c < 4; c++)
    p->lrud[c] = NAN;
  s->slots[h] = ++s->n_points;
  *index = s->n_points - 1;
  return KARST_SUCCESS;
}

static karst_error_t rehash_labels(karst_i_survey_t *s, karst_int_t n_slots) {
  char **names = calloc((size_t)n_slots, sizeof *names);
  karst_int_t *pts = calloc((size_t)n_slots, sizeof *pts);
  if (!names || !pts) {
    free(names);
    free(pts);
    return KARST_ENOMEM;
  }
  for (karst_int_t i = 0; i < s->n_lab_slots; i++) {
    if (!s->lab_names[i]) continue;
    uint64_t h = str_hash(s->lab_names[i]) & (uint64_t)(n_slots - 1);
    while (names[h])
      h = (h + 1) & (uint64_t)(n_slots - 1);
    names[h] = s->lab_names[i];
    pts[h] = s->lab_point[i];
  }
  free(s->lab_names);
  free(s->lab_point);
  s->lab_names = names;
  s->lab_point = pts;
  s->n_lab_slots = n_slots;
  return KARST_SUCCESS;
}

karst_int_t karst_i_survey_lookup(const karst_i_survey_t *s, const char *label) {
  if (!s->n_lab_slots) return -1;
  uint64_t mask = (uint64_t)(s->n_lab_slots - 1);
  for (uint64_t h = str_hash(label) & mask; s->lab_names[h]; h = (h + 1) & mask)
    if (strcmp(s->lab_names[h], label) == 0) return s->lab_point[h];
  return -1;
}

karst_error_t karst_i_survey_name(karst_i_survey_t *s, karst_int_t p, const char *label) {
  karst_error_t err;
  if (karst_i_survey_lookup(s, label) >= 0) return KARST_SUCCESS; /* first position wins */
  if ((s->n_labels + 1) * MAX_LOAD_DEN > s->n_lab_slots * MAX_LOAD_NUM &&
      (err = rehash_labels(s, s->n_lab_slots ? 2 * s->n_lab_slots : 64)))
    return err;
  char *copy = strdup(label);
  if (!copy) return KARST_ENOMEM;
  uint64_t mask = (uint64_t)(s->n_lab_slots - 1), h = str_hash(label) & mask;
  while (s->lab_names[h])
    h = (h + 1) & mask;
  s->lab_names[h] = copy;
  s->lab_point[h] = p;
  s->n_labels++;
  if (!s->points[p].label) s->points[p].label = copy;
  return KARST_SUCCESS;
}

karst_error_t karst_i_survey_leg(karst_i_survey_t *s, karst_int_t a, karst_int_t b) {
  if (s->n_legs == s->cap_legs) {
    karst_int_t cap = s->cap_legs ? 2 * s->cap_legs : 64;
    karst_int_t *l = realloc(s->legs, (size_t)cap * 2 * sizeof *l);
    if (!l) return KARST_ENOMEM;
    s->legs = l;
    s->cap_legs = cap;
  }
  s->legs[2 * s->n_legs] = a;
  s->legs[2 * s->n_legs + 1] = b;
  s->n_legs++;
  return KARST_SUCCESS;
}

karst_error_t karst_i_survey_build(karst_ctx_t *ctx, const karst_i_survey_t *s, int with_lrud,
                                   karst_network_t *net, karst_int_t *n_zero) {
  karst_error_t err = KARST_SUCCESS;
  karst_int_t zero = 0;
  karst_int_t *node_of = malloc((size_t)(s->n_points ? s->n_points : 1) * sizeof *node_of);
  if (!node_of) {
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory building the survey network");
    goto cleanup;
  }
  for (karst_int_t i = 0; i < s->n_points; i++)
    node_of[i] = -1;
  /* Nodes in order of first appearance among the points that a kept leg uses. */
  for (karst_int_t l = 0; l < s->n_legs; l++) {
    karst_int_t a = s->legs[2 * l], b = s->legs[2 * l + 1];
    if (a == b) {
      zero++;
      continue;
    }
    node_of[a] = node_of[b] = 0; /* mark used */
  }
  for (karst_int_t p = 0; p < s->n_points; p++) {
    if (node_of[p] < 0) continue;
    const karst_i_cmkey_t k = s->points[p].key;
    if ((err = karst_network_add_node(net, (double)k.x / KARST_I_SURVEY_CM_PER_M,
                                      (double)k.y / KARST_I_SURVEY_CM_PER_M,
                                      (double)k.z / KARST_I_SURVEY_CM_PER_M, &node_of[p])))
      goto nomem;
  }
  for (karst_int_t l = 0; l < s->n_legs; l++) {
    karst_int_t a = s->legs[2 * l], b = s->legs[2 * l + 1];
    if (a != b && (err = karst_network_add_edge(net, node_of[a], node_of[b], NULL))) goto nomem;
  }
  for (karst_int_t p = 0; p < s->n_points; p++)
    if (node_of[p] >= 0 && s->points[p].label &&
        (err = karst_network_set_label(net, node_of[p], s->points[p].label)))
      goto nomem;
  if (with_lrud) {
    double *lrud = NULL;
    if ((err = karst_network_attr_add(net, KARST_ATTR_NODE, "lrud", 4, 0, &lrud))) goto nomem;
    for (karst_int_t p = 0; p < s->n_points; p++)
      if (node_of[p] >= 0) memcpy(lrud + 4 * node_of[p], s->points[p].lrud, sizeof(double[4]));
  }
  int any_entrance = 0;
  for (karst_int_t p = 0; p < s->n_points && !any_entrance; p++)
    any_entrance = node_of[p] >= 0 && s->points[p].entrance;
  if (any_entrance) {
    double *ent = NULL;
    if ((err = karst_network_attr_add(net, KARST_ATTR_NODE, "entrance", 1, 1, &ent))) goto nomem;
    for (karst_int_t p = 0; p < s->n_points; p++)
      if (node_of[p] >= 0) ent[node_of[p]] = s->points[p].entrance;
  }
  if (n_zero) *n_zero = zero;
  goto cleanup;
nomem:
  err = karst_set_error(ctx, err, "cannot build the survey network: %s", karst_strerror(err));
cleanup:
  if (err) karst_network_destroy(net);
  free(node_of);
  return err;
}

karst_error_t karst_i_read_file(karst_ctx_t *ctx, const char *path, unsigned char **data,
                                size_t *len) {
  return karst_i_read_regular(ctx, path, "survey", KARST_SURVEY_MAX_BYTES, data, len);
}
