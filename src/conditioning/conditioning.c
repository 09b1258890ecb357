/* Conditioning on surveys (include/karst/conditioning.h, docs/generation.md "Conditioning"):
 * reading the surveys a scenario names into its frame, checking them against the domain and the
 * terrain, and the hooks of the pipeline that put their stations among the samples and their legs
 * into every network. */
#include "karst/conditioning.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/crs.h"
#include "karst/geology.h"
#include "karst/readers.h"

void karst_survey_set_free(karst_survey_set_t *s) {
  if (!s) return;
  for (karst_int_t i = 0; i < s->n_stations; i++)
    free(s->labels ? s->labels[i] : NULL);
  for (int i = 0; i < s->n_surveys; i++) {
    free(s->source_crs ? s->source_crs[i] : NULL);
    free(s->conversion ? s->conversion[i] : NULL);
  }
  free(s->xyz);
  free(s->labels);
  free(s->entrance);
  free(s->lrud);
  free(s->survey);
  free(s->legs);
  free(s->component);
  free(s->component_station);
  free(s->source_crs);
  free(s->conversion);
  free(s->accuracy);
  free(s);
}

/* Open-addressing set of stations keyed by their exact coordinates (bit patterns), so that two
 * surveys that put a station at the same point share it. */
typedef struct {
  karst_int_t *slot; /* station index + 1, 0 empty */
  size_t cap;
} station_map_t;

static uint64_t bits(double v) {
  uint64_t u;
  v = v == 0 ? 0.0 : v; /* -0 and +0 are one point */
  memcpy(&u, &v, sizeof u);
  return u;
}

static size_t hash_point(const double *p, size_t cap) {
  uint64_t h = 1469598103934665603ULL;
  for (int k = 0; k < 3; k++) {
    h ^= bits(p[k]);
    h *= 0x100000001b3ULL;
    h ^= h >> 29;
  }
  return (size_t)h & (cap - 1);
}

static int same_point(const double *a, const double *b) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* Grow every per-station array of @p s to hold @p cap stations. */
static int reserve_stations(karst_survey_set_t *s, karst_int_t cap) {
  double *xyz = realloc(s->xyz, (size_t)cap * 3 * sizeof *xyz);
  if (!xyz) return -1;
  s->xyz = xyz;
  char **lab = realloc(s->labels, (size_t)cap * sizeof *lab);
  if (!lab) return -1;
  s->labels = lab;
  unsigned char *ent = realloc(s->entrance, (size_t)cap);
  if (!ent) return -1;
  s->entrance = ent;
  double *lrud = realloc(s->lrud, (size_t)cap * 4 * sizeof *lrud);
  if (!lrud) return -1;
  s->lrud = lrud;
  int *sv = realloc(s->survey, (size_t)cap * sizeof *sv);
  if (!sv) return -1;
  s->survey = sv;
  return 0;
}

/* The connected pieces of the survey (union-find over the legs) and each piece's lowest station
 * (where water leaves it; ties: the first station). O(stations + legs α). */
static karst_error_t find_components(karst_ctx_t *ctx, karst_survey_set_t *s) {
  karst_int_t n = s->n_stations;
  karst_int_t *parent = malloc((size_t)(n > 0 ? n : 1) * sizeof *parent);
  s->component = malloc((size_t)(n > 0 ? n : 1) * sizeof *s->component);
  if (!parent || !s->component) {
    free(parent);
    return karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory");
  }
  for (karst_int_t i = 0; i < n; i++)
    parent[i] = i;
  for (karst_int_t l = 0; l < s->n_legs; l++) {
    karst_int_t a = s->legs[2 * l], b = s->legs[2 * l + 1];
    while (parent[a] != a)
      a = parent[a] = parent[parent[a]];
    while (parent[b] != b)
      b = parent[b] = parent[parent[b]];
    if (a != b) parent[a > b ? a : b] = a < b ? a : b;
  }
  karst_int_t nc = 0;
  for (karst_int_t i = 0; i < n; i++) {
    karst_int_t r = i;
    while (parent[r] != r)
      r = parent[r];
    s->component[i] = r == i ? nc++ : s->component[r];
  }
  s->n_components = nc;
  s->component_station = malloc((size_t)(nc > 0 ? nc : 1) * sizeof *s->component_station);
  free(parent);
  if (!s->component_station)
    return karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory");
  for (karst_int_t c = 0; c < nc; c++)
    s->component_station[c] = -1;
  for (karst_int_t i = 0; i < n; i++) {
    karst_int_t *low = &s->component_station[s->component[i]];
    if (*low < 0 || s->xyz[3 * i + 2] < s->xyz[3 * *low + 2]) *low = i;
  }
  return KARST_SUCCESS;
}

/* "FILE:LINE:COLUMN: conditioning.surveys[i]" of a survey, for messages. */
static void survey_where(const karst_scenario_t *sc, int i, char *buf, size_t n) {
  const karst_survey_def_t *d = &sc->conditioning.surveys[i];
  if (sc->path && d->line > 0)
    snprintf(buf, n, "%s:%d:%d: conditioning.surveys[%d] '%s'", sc->path, d->line, d->column, i,
             d->path);
  else
    snprintf(buf, n, "conditioning.surveys[%d] '%s'", i, d->path);
}

/* Put "WHERE[WHAT]: " before ctx's message: the scenario's position first, as for every file a
 * scenario names. */
static void prefix_where(karst_ctx_t *ctx, const char *where, const char *what) {
  char msg[KARST_ERRMSG_MAX];
  snprintf(msg, sizeof msg, "%s", ctx->errmsg);
  snprintf(ctx->errmsg, KARST_ERRMSG_MAX, "%.*s%.64s: %.*s", KARST_ERRMSG_MAX / 2 - 80, where, what,
           KARST_ERRMSG_MAX / 2 - 8, msg);
}

/* Read survey @p i into @p s (appending). */
static karst_error_t load_one(karst_ctx_t *ctx, karst_scenario_t *sc, int i, karst_survey_set_t *s,
                              station_map_t *map) {
  const karst_survey_def_t *d = &sc->conditioning.surveys[i];
  karst_network_t net;
  karst_network_init(&net);
  karst_crs_t *src = NULL;
  karst_int_t *node_station = NULL;
  char where[KARST_ERRMSG_MAX / 2];
  survey_where(sc, i, where, sizeof where);
  karst_error_t err = karst_read_network(ctx, d->path, KARST_FORMAT_AUTO, &net);
  if (err) {
    prefix_where(ctx, where, "");
    goto cleanup;
  }
  if (net.n_edges == 0) {
    err = karst_set_error(ctx, KARST_EINVAL,
                          "%s holds no leg once splay, surface and duplicate legs are left out",
                          where);
    goto cleanup;
  }
  const char *crs_text = d->crs ? d->crs : net.crs;
  if (crs_text && !(s->source_crs[i] = strdup(crs_text))) goto nomem;
  if (crs_text && sc->crs_frame) {
    if ((err = karst_crs_create(ctx, crs_text, &src))) {
      prefix_where(ctx, where, d->crs ? " crs" : " (the file's own CRS)");
      goto cleanup;
    }
    char what[512];
    if ((err = karst_crs_describe(ctx, src, sc->crs_frame, net.xyz[0], net.xyz[1], what,
                                  sizeof what, &s->accuracy[i])))
      goto cleanup;
    if (!(s->conversion[i] = strdup(what))) goto nomem;
    if ((err = karst_crs_transform(ctx, src, sc->crs_frame, net.n_nodes, net.xyz))) {
      size_t len = strlen(ctx->errmsg);
      snprintf(ctx->errmsg + len, KARST_ERRMSG_MAX - len, " (converting %s into '%s')", where,
               sc->crs);
      goto cleanup;
    }
  }
  const karst_attr_t *ent = karst_network_attr_find(&net, KARST_ATTR_NODE, "entrance");
  const karst_attr_t *lrud = karst_network_attr_find(&net, KARST_ATTR_NODE, "lrud");
  if (lrud && lrud->ncomp != 4) lrud = NULL;
  node_station = malloc((size_t)net.n_nodes * sizeof *node_station);
  if (!node_station) goto nomem;
  for (karst_int_t v = 0; v < net.n_nodes; v++) {
    const double *p = &net.xyz[3 * v];
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
      err = karst_set_error(ctx, KARST_EINVAL, "%s: station %lld has a non-finite coordinate",
                            where, (long long)v);
      goto cleanup;
    }
    /* The station set at most half full. */
    if (2 * (size_t)(s->n_stations + 1) > map->cap) {
      size_t cap = map->cap ? 2 * map->cap : 1024;
      karst_int_t *slot = calloc(cap, sizeof *slot);
      if (!slot) goto nomem;
      for (size_t k = 0; k < map->cap; k++)
        if (map->slot[k]) {
          size_t h = hash_point(&s->xyz[3 * (map->slot[k] - 1)], cap);
          while (slot[h])
            h = (h + 1) & (cap - 1);
          slot[h] = map->slot[k];
        }
      free(map->slot);
      map->slot = slot;
      map->cap = cap;
      if (reserve_stations(s, (karst_int_t)(cap / 2))) goto nomem;
    }
    size_t h = hash_point(p, map->cap);
    while (map->slot[h] && !same_point(&s->xyz[3 * (map->slot[h] - 1)], p))
      h = (h + 1) & (map->cap - 1);
    if (map->slot[h]) {
      karst_int_t st = map->slot[h] - 1;
      node_station[v] = st;
      if (ent && ent->data[v]) s->entrance[st] = 1;
      continue;
    }
    karst_int_t st = s->n_stations++;
    map->slot[h] = st + 1;
    node_station[v] = st;
    memcpy(&s->xyz[3 * st], p, 3 * sizeof *p);
    s->labels[st] = NULL;
    if (net.node_labels && net.node_labels[v] && !(s->labels[st] = strdup(net.node_labels[v])))
      goto nomem;
    s->entrance[st] = ent && ent->data[v] != 0;
    for (int c = 0; c < 4; c++)
      s->lrud[4 * st + c] = lrud ? lrud->data[4 * v + c] : NAN;
    s->survey[st] = i;
  }
  karst_int_t *legs = realloc(s->legs, (size_t)(s->n_legs + net.n_edges) * 2 * sizeof *legs);
  if (!legs) goto nomem;
  s->legs = legs;
  for (karst_int_t e = 0; e < net.n_edges; e++) {
    karst_int_t a = node_station[net.edges[2 * e]], b = node_station[net.edges[2 * e + 1]];
    if (a == b) continue; /* both ends merged: no passage */
    legs[2 * s->n_legs] = a < b ? a : b;
    legs[2 * s->n_legs + 1] = a < b ? b : a;
    s->n_legs++;
  }
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", where);
cleanup:
  free(node_station);
  karst_crs_free(src);
  karst_network_destroy(&net);
  return err;
}

static int cmp_leg(const void *x, const void *y) {
  const karst_int_t *a = x, *b = y;
  if (a[0] != b[0]) return a[0] < b[0] ? -1 : 1;
  return (a[1] > b[1]) - (a[1] < b[1]);
}

/**
 * karst_conditioning_load: see conditioning.h. Repeated legs (the same two stations, e.g. a leg
 * surveyed twice that the reader did not flag duplicate) are kept once.
 * @return KARST_SUCCESS; the reader's error with the survey's place in the scenario appended;
 *         KARST_EINVAL for a survey without legs; the CRS errors; KARST_ENOMEM.
 * Time complexity: O(stations + legs log legs) after the readers.
 */
karst_error_t karst_conditioning_load(karst_ctx_t *ctx, karst_scenario_t *sc) {
  karst_conditioning_t *c = &sc->conditioning;
  karst_survey_set_free(c->data);
  c->data = NULL;
  if (c->n_surveys < 1) return KARST_SUCCESS;
  karst_error_t err = KARST_SUCCESS;
  station_map_t map = {NULL, 0};
  karst_survey_set_t *s = calloc(1, sizeof *s);
  if (!s) return karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory");
  s->n_surveys = c->n_surveys;
  s->source_crs = calloc((size_t)c->n_surveys, sizeof *s->source_crs);
  s->conversion = calloc((size_t)c->n_surveys, sizeof *s->conversion);
  s->accuracy = calloc((size_t)c->n_surveys, sizeof *s->accuracy);
  if (!s->source_crs || !s->conversion || !s->accuracy) {
    err = karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory");
    goto cleanup;
  }
  for (int i = 0; i < c->n_surveys; i++)
    if ((err = load_one(ctx, sc, i, s, &map))) goto cleanup;
  /* Legs once each, in a canonical order. */
  qsort(s->legs, (size_t)s->n_legs, 2 * sizeof *s->legs, cmp_leg);
  karst_int_t m = 0;
  for (karst_int_t l = 0; l < s->n_legs; l++)
    if (m == 0 || cmp_leg(&s->legs[2 * l], &s->legs[2 * (m - 1)]) != 0) {
      s->legs[2 * m] = s->legs[2 * l], s->legs[2 * m + 1] = s->legs[2 * l + 1];
      m++;
    }
  s->n_legs = m;
  for (karst_int_t l = 0; l < s->n_legs; l++) {
    const double *a = &s->xyz[3 * s->legs[2 * l]], *b = &s->xyz[3 * s->legs[2 * l + 1]];
    s->length += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                      (a[2] - b[2]) * (a[2] - b[2]));
  }
  if ((err = find_components(ctx, s))) goto cleanup;
  c->data = s;
  s = NULL;
cleanup:
  free(map.slot);
  karst_survey_set_free(s);
  return err;
}

/** Index of the station named @p name (the first so named), or -1. O(stations). */
karst_int_t karst_survey_find_station(const karst_survey_set_t *s, const char *name) {
  if (!s || !name) return -1;
  for (karst_int_t i = 0; i < s->n_stations; i++)
    if (s->labels[i] && !strcmp(s->labels[i], name)) return i;
  return -1;
}

/**
 * karst_conditioning_check: see conditioning.h. The message names the station farthest outside
 * the domain (by the largest distance along an axis) or highest above the terrain.
 * @return KARST_SUCCESS or KARST_ERANGE. Time complexity: O(stations) terrain queries.
 */
karst_error_t karst_conditioning_check(karst_ctx_t *ctx, const karst_scenario_t *sc) {
  const karst_survey_set_t *s = sc->conditioning.data;
  if (!s) return KARST_SUCCESS;
  static const char axis[3] = {'x', 'y', 'z'};
  karst_int_t worst = -1, n_out = 0;
  double by = 0;
  int worst_axis = 0;
  for (karst_int_t i = 0; i < s->n_stations; i++) {
    const double *p = &s->xyz[3 * i];
    for (int a = 0; a < 3; a++) {
      double d = fmax(sc->domain_min[a] - p[a], p[a] - sc->domain_max[a]);
      if (d > 0) {
        n_out++;
        if (d > by) by = d, worst = i, worst_axis = a;
        break;
      }
    }
  }
  char where[KARST_ERRMSG_MAX / 2];
  if (worst >= 0) {
    const double *p = &s->xyz[3 * worst];
    survey_where(sc, s->survey[worst], where, sizeof where);
    return karst_set_error(
        ctx, KARST_ERANGE,
        "%s lies outside the domain: station '%s' at (%.2f, %.2f, %.2f) is %.2f m beyond it in %c "
        "(the domain spans %c in [%g, %g] m), and %lld of the %lld stations are outside; enlarge "
        "the domain or check the survey's coordinate system%s%s",
        where, s->labels[worst] ? s->labels[worst] : "(unnamed)", p[0], p[1], p[2], by,
        axis[worst_axis], axis[worst_axis], sc->domain_min[worst_axis], sc->domain_max[worst_axis],
        (long long)n_out, (long long)s->n_stations,
        s->source_crs[s->survey[worst]] ? ", here " : "",
        s->source_crs[s->survey[worst]] ? s->source_crs[s->survey[worst]] : "");
  }
  n_out = 0, by = 0;
  double ground = 0;
  for (karst_int_t i = 0; i < s->n_stations; i++) {
    const double *p = &s->xyz[3 * i];
    double h = karst_terrain_height(&sc->terrain, p[0], p[1]);
    if (p[2] > h) {
      n_out++;
      if (p[2] - h > by) by = p[2] - h, worst = i, ground = h;
    }
  }
  if (worst >= 0) {
    const double *p = &s->xyz[3 * worst];
    survey_where(sc, s->survey[worst], where, sizeof where);
    return karst_set_error(ctx, KARST_ERANGE,
                           "%s lies above the terrain: station '%s' at (%.2f, %.2f, %.2f) is "
                           "%.2f m above the ground (%.2f m there), and %lld of the %lld stations "
                           "are above it; a surveyed passage must lie in the bedrock (check the "
                           "terrain and the survey's heights)",
                           where, s->labels[worst] ? s->labels[worst] : "(unnamed)", p[0], p[1],
                           p[2], by, ground, (long long)n_out, (long long)s->n_stations);
  }
  return KARST_SUCCESS;
}

/**
 * karst_conditioning_add_samples: see conditioning.h. A station a key point sits on (its
 * station_index, or the same position) is that key point's sample, so no two samples coincide.
 * Time complexity: O(stations + key points) expected.
 */
karst_error_t karst_conditioning_add_samples(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                             karst_samples_t *samples,
                                             karst_int_t *station_vertex) {
  const karst_survey_set_t *s = sc->conditioning.data;
  if (!s) return KARST_SUCCESS;
  for (karst_int_t i = 0; i < s->n_stations; i++)
    station_vertex[i] = -1;
  for (int k = 0; k < sc->n_key_points; k++) {
    const karst_keypoint_t *kp = &sc->key_points[k];
    if (kp->station_index >= 0 && kp->station_index < s->n_stations)
      station_vertex[kp->station_index] = k;
  }
  for (karst_int_t i = 0; i < s->n_stations; i++) {
    if (station_vertex[i] >= 0) continue;
    for (int k = 0; k < sc->n_key_points && station_vertex[i] < 0; k++)
      if (same_point(sc->key_points[k].p, &s->xyz[3 * i])) station_vertex[i] = k;
    if (station_vertex[i] >= 0) continue;
    if (karst_samples_add(samples, &s->xyz[3 * i], KARST_SAMPLE_SURVEY))
      return karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory for the stations");
    station_vertex[i] = samples->n - 1;
  }
  return KARST_SUCCESS;
}

/** cost_factor × @p lb_per_metre when conditioning on a survey, else @p lb_per_metre. O(1). */
double karst_conditioning_lower_bound_per_metre(const karst_scenario_t *sc, double lb_per_metre) {
  if (!sc->conditioning.data || sc->conditioning.data->n_legs == 0) return lb_per_metre;
  return fmin(1.0, sc->conditioning.cost_factor) * lb_per_metre;
}

/**
 * karst_conditioning_lay: see conditioning.h. Each leg is a path of two vertices (its own
 * branch id), laid before any route, so later routes that follow it share its edge.
 * Time complexity: O(legs × degree).
 */
karst_error_t karst_conditioning_lay(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                     const karst_graph_t *g, const karst_int_t *station_vertex,
                                     karst_skeleton_t *sk) {
  const karst_survey_set_t *s = sc->conditioning.data;
  double *d;
  if (karst_network_attr_add(&sk->net, KARST_ATTR_EDGE, "observed", 1, 1, &d) ||
      karst_network_attr_add(&sk->net, KARST_ATTR_NODE, "observed", 1, 1, &d))
    return karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory");
  if (!s) return KARST_SUCCESS;
  karst_path_t path;
  karst_path_init(&path);
  karst_error_t err = KARST_SUCCESS;
  karst_int_t v2[2];
  path.v = v2;
  path.n = 2;
  for (karst_int_t l = 0; l < s->n_legs && !err; l++) {
    karst_int_t e0 = sk->net.n_edges;
    v2[0] = station_vertex[s->legs[2 * l]];
    v2[1] = station_vertex[s->legs[2 * l + 1]];
    if (v2[0] == v2[1]) continue;
    if ((err = karst_skeleton_add_path(ctx, sk, g, &path, 0))) break;
    if (sk->net.n_edges > e0)
      karst_network_attr_find(&sk->net, KARST_ATTR_EDGE, "observed")->data[e0] = 1;
  }
  double *nobs = karst_network_attr_find(&sk->net, KARST_ATTR_NODE, "observed")->data;
  for (karst_int_t i = 0; i < s->n_stations && !err; i++) {
    karst_int_t node = sk->node_of_vertex[station_vertex[i]];
    if (node < 0) continue; /* a station on no leg (cannot happen: readers keep leg ends) */
    nobs = karst_network_attr_find(&sk->net, KARST_ATTR_NODE, "observed")->data;
    nobs[node] = 1;
    if (s->labels[i] && karst_network_set_label(&sk->net, node, s->labels[i]))
      err = karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory");
  }
  return err;
}

/**
 * karst_conditioning_assign_springs: see conditioning.h.
 * Time complexity: O(stations + key points + edges).
 */
karst_error_t karst_conditioning_assign_springs(karst_ctx_t *ctx, const karst_scenario_t *view,
                                                const karst_int_t *station_vertex,
                                                const int *key_spring, karst_skeleton_t *sk) {
  const karst_survey_set_t *s = view->conditioning.data;
  if (!s || !station_vertex || !key_spring) return KARST_SUCCESS;
  int *comp_spring =
      malloc((size_t)(s->n_components > 0 ? s->n_components : 1) * sizeof *comp_spring);
  if (!comp_spring) return karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory");
  for (karst_int_t c = 0; c < s->n_components; c++)
    comp_spring[c] = -1;
  for (int k = 0; k < view->n_key_points; k++) {
    karst_int_t st = view->key_points[k].station_index;
    if (st < 0 || st >= s->n_stations || key_spring[k] < 0) continue;
    if (comp_spring[s->component[st]] < 0) comp_spring[s->component[st]] = key_spring[k];
  }
  double *nsp = karst_network_attr_find(&sk->net, KARST_ATTR_NODE, "spring")->data;
  for (karst_int_t i = 0; i < s->n_stations; i++) {
    karst_int_t node = sk->node_of_vertex[station_vertex[i]];
    int sp = comp_spring[s->component[i]];
    if (node >= 0 && sp >= 0 && nsp[node] < 0) nsp[node] = sp;
  }
  const karst_attr_t *obs = karst_network_attr_find(&sk->net, KARST_ATTR_EDGE, "observed");
  double *esp = karst_network_attr_find(&sk->net, KARST_ATTR_EDGE, "spring")->data;
  for (karst_int_t e = 0; obs && e < sk->net.n_edges; e++)
    if (obs->data[e] != 0 && esp[e] < 0) esp[e] = nsp[sk->net.edges[2 * e]];
  free(comp_spring);
  return KARST_SUCCESS;
}

/* The passage radius a station's LRUD gives (see karst_conditioning_passage_radius), or NAN. */
static double station_radius(const double *lrud) {
  double sum = 0;
  int n = 0;
  if (lrud[0] >= 0 && lrud[1] >= 0) sum += 0.5 * (lrud[0] + lrud[1]), n++;
  if (lrud[2] >= 0 && lrud[3] >= 0) sum += 0.5 * (lrud[2] + lrud[3]), n++;
  return n ? sum / n : NAN;
}

/**
 * karst_conditioning_passage_radius: see conditioning.h. The original nodes of @p sk keep their
 * indices in @p out (karst_amplification_displace adds new nodes after them).
 * Time complexity: O(stations + nodes + edges).
 */
karst_error_t karst_conditioning_passage_radius(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                                const karst_int_t *station_vertex,
                                                const karst_skeleton_t *sk, karst_network_t *out) {
  const karst_survey_set_t *s = sc->conditioning.data;
  const karst_attr_t *obs = karst_network_attr_find(out, KARST_ATTR_EDGE, "observed");
  karst_attr_t *rad = karst_network_attr_find(out, KARST_ATTR_EDGE, "radius");
  if (!s || !obs || !rad) return KARST_SUCCESS;
  double *node_r = malloc((size_t)(out->n_nodes > 0 ? out->n_nodes : 1) * sizeof *node_r);
  if (!node_r) return karst_set_error(ctx, KARST_ENOMEM, "conditioning: out of memory");
  for (karst_int_t v = 0; v < out->n_nodes; v++)
    node_r[v] = NAN;
  for (karst_int_t i = 0; i < s->n_stations; i++) {
    karst_int_t node = sk->node_of_vertex[station_vertex[i]];
    if (node >= 0 && node < out->n_nodes && isnan(node_r[node]))
      node_r[node] = station_radius(&s->lrud[4 * i]);
  }
  for (karst_int_t e = 0; e < out->n_edges; e++) {
    if (obs->data[e] == 0) continue;
    double ra = node_r[out->edges[2 * e]], rb = node_r[out->edges[2 * e + 1]];
    double r = isnan(ra) ? rb : isnan(rb) ? ra : 0.5 * (ra + rb);
    if (r > 0) rad->data[e] = r;
  }
  free(node_r);
  return KARST_SUCCESS;
}
