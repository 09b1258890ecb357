/* run.json: what a realisation was made from (scenario path and hash, seed,
 * every effective parameter) and what it produced (counts, stage times). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/amplification.h"
#include "karst/classification.h"
#include "karst/conditioning.h"
#include "karst/generate.h"
#include "karst/io.h"
#include "karst/version.h"

/* A JSON number (shortest round-trip form), or null for NaN / infinities. */
static void json_num(FILE *fp, double v) {
  if (!isfinite(v)) {
    fputs("null", fp);
    return;
  }
  char buf[32];
  for (int prec = 15; prec <= 17; prec++) {
    snprintf(buf, sizeof buf, "%.*g", prec, v);
    double back;
    if (sscanf(buf, "%lf", &back) == 1 && back == v) break;
  }
  fputs(buf, fp);
}

static void kv_num(FILE *fp, const char *ind, const char *key, double v, int last) {
  fprintf(fp, "%s\"%s\": ", ind, key);
  json_num(fp, v);
  fputs(last ? "\n" : ",\n", fp);
}

static void vec3(FILE *fp, const double *v) {
  fputc('[', fp);
  for (int k = 0; k < 3; k++) {
    json_num(fp, v[k]);
    if (k < 2) fputs(", ", fp);
  }
  fputc(']', fp);
}

static const char *perm_kind(karst_perm_kind_t k) {
  static const char *const names[] = {"sphere", "stratum", "union", "intersection", "blend"};
  return (int)k >= 0 && k <= KARST_PERM_BLEND ? names[k] : "unknown";
}

static void perm_json(FILE *fp, const karst_perm_node_t *n) {
  fprintf(fp, "{\"kind\": \"%s\"", perm_kind(n->kind));
  if (n->kind == KARST_PERM_SPHERE) {
    fputs(", \"resistance\": ", fp), json_num(fp, n->resistance);
    fputs(", \"center\": ", fp), vec3(fp, n->center);
    fputs(", \"radius\": ", fp), json_num(fp, n->radius);
    fputs(", \"falloff\": ", fp), json_num(fp, n->falloff);
  } else if (n->kind == KARST_PERM_STRATUM) {
    fputs(", \"resistance\": ", fp), json_num(fp, n->resistance);
    fputs(", \"bottom\": ", fp), json_num(fp, n->bottom);
    fputs(", \"top\": ", fp), json_num(fp, n->top);
  }
  fputs(", \"weight\": ", fp), json_num(fp, n->weight);
  if (n->n_children > 0) {
    fputs(", \"children\": [", fp);
    for (int i = 0; i < n->n_children; i++) {
      if (i) fputs(", ", fp);
      perm_json(fp, &n->children[i]);
    }
    fputc(']', fp);
  }
  fputc('}', fp);
}

/* A file named in the parameters, with its FNV-1a hash so run.json says which file was used. */
static void file_json(FILE *fp, const char *key, const char *path) {
  char hash[17] = "";
  karst_ctx_t hctx;
  karst_ctx_init(&hctx);
  fprintf(fp, "\"%s\": ", key);
  karst_json_string(fp, path);
  fprintf(fp, ", \"%s_hash\": ", key);
  if (path && karst_file_hash(&hctx, path, hash) == KARST_SUCCESS)
    karst_json_string(fp, hash);
  else
    fputs("null", fp);
}

/* A surface definition: null when not given, its file, or its plane. */
static void surface_json(FILE *fp, const karst_surface_def_t *d) {
  if (!d->given) {
    fputs("null", fp);
    return;
  }
  fputc('{', fp);
  if (d->path) {
    file_json(fp, "surface", d->path);
  } else {
    fputs("\"elevation\": ", fp), json_num(fp, d->elevation);
    fputs(", \"dip\": ", fp), json_num(fp, d->dip);
    fputs(", \"dip_direction\": ", fp), json_num(fp, d->dip_direction);
    fputs(", \"origin\": [", fp), json_num(fp, d->origin[0]), fputs(", ", fp),
        json_num(fp, d->origin[1]), fputc(']', fp);
  }
  fputc('}', fp);
}

static const char *keypoint_type(karst_keypoint_type_t t) {
  return t == KARST_KEYPOINT_SINK ? "sink" : (t == KARST_KEYPOINT_SPRING ? "spring" : "waypoint");
}

/* The coordinate system, the conditioning surveys and the generations (docs/scenario.md,
 * "Coordinates", "Conditioning", "Generations"): the last members of "parameters". */
static void frame_json(FILE *fp, const karst_scenario_t *sc) {
  fputs("    \"crs\": ", fp);
  if (sc->crs)
    karst_json_string(fp, sc->crs);
  else
    fputs("null", fp);
  fputs(",\n    \"conditioning\": ", fp);
  const karst_conditioning_t *c = &sc->conditioning;
  const karst_survey_set_t *s = c->data;
  if (c->n_surveys > 0) {
    fputs("{\"surveys\": [", fp);
    for (int i = 0; i < c->n_surveys; i++) {
      fputs(i ? ", {\"file\": " : "{\"file\": ", fp);
      karst_json_string(fp, c->surveys[i].path);
      fputs(", \"crs\": ", fp);
      const char *from = c->surveys[i].crs       ? c->surveys[i].crs
                         : s && s->source_crs[i] ? s->source_crs[i]
                                                 : NULL;
      if (from)
        karst_json_string(fp, from);
      else
        fputs("null", fp);
      fputs(", \"conversion\": ", fp);
      if (s && s->conversion[i])
        karst_json_string(fp, s->conversion[i]);
      else
        fputs("null", fp);
      fputs(", \"conversion_accuracy\": ", fp);
      json_num(fp, s && s->accuracy[i] >= 0 ? s->accuracy[i] : NAN);
      fputc('}', fp);
    }
    fputs("], \"cost_factor\": ", fp);
    json_num(fp, c->cost_factor);
    static const char *const sinks[] = {"none", "entrances", "list"};
    fprintf(fp, ", \"sinks\": \"%s\", \"generation\": %d", sinks[c->sinks % 3], c->generation);
    fprintf(fp, ", \"stations\": %lld, \"legs\": %lld, \"pieces\": %lld, \"length\": ",
            (long long)(s ? s->n_stations : 0), (long long)(s ? s->n_legs : 0),
            (long long)(s ? s->n_components : 0));
    json_num(fp, s ? s->length : 0);
    fputc('}', fp);
  } else {
    fputs("null", fp);
  }
  fputs(",\n    \"generations\": [", fp);
  for (int i = 0; i < sc->n_generations; i++) {
    const karst_generation_t *G = &sc->generations[i];
    fputs(i ? ",\n      {\"name\": " : "\n      {\"name\": ", fp);
    karst_json_string(fp, G->name);
    fputs(", \"water_table\": ", fp), surface_json(fp, &G->water_table);
    fputs(", \"key_points\": [", fp);
    for (int k = 0, n = 0; k < sc->n_key_points; k++)
      if (sc->key_points[k].generation == i + 1) {
        fputs(n++ ? ", " : "", fp);
        karst_json_string(fp, sc->key_points[k].name);
      }
    fputs("], \"cohesion\": ", fp), json_num(fp, G->cohesion);
    fputs(", \"gamma\": ", fp), json_num(fp, G->gamma);
    fputs(", \"reuse\": ", fp), json_num(fp, G->reuse);
    fputs(", \"vadose_factor\": ", fp), json_num(fp, G->routing.vadose_factor);
    fprintf(fp, ", \"amplification_steps\": %d}", G->amplification.steps);
  }
  fputs("]\n", fp);
}

/**
 * Write every effective parameter of @p sc (and the amplification constants)
 * as the members of a JSON object, one per line at a 4-space indent, without
 * the braces: the "parameters" object of run.json and of ensemble.json, so the
 * two cannot drift apart. Numbers are written so that they round-trip.
 * Time complexity: O(size of the scenario).
 */
void karst_generate_write_parameters(FILE *fp, const karst_scenario_t *sc) {
  const char *I = "    ";
  fputs("    \"name\": ", fp);
  karst_json_string(fp, sc->name);
  fputs(",\n    \"domain_min\": ", fp), vec3(fp, sc->domain_min);
  fputs(",\n    \"domain_max\": ", fp), vec3(fp, sc->domain_max);
  fputs(",\n    \"terrain\": {", fp);
  if (sc->terrain.is_grid) {
    /* The georeference as read (ESRI grid: lower-left corner and cell centre, cell size) and
     * the file's hash, so that run.json says which surface the run used. */
    const karst_terrain_t *tr = &sc->terrain;
    char hash[17] = "";
    karst_ctx_t hctx;
    karst_ctx_init(&hctx);
    fputs("\"grid\": ", fp), karst_json_string(fp, tr->path);
    fputs(", \"grid_hash\": ", fp);
    if (tr->path && karst_file_hash(&hctx, tr->path, hash) == KARST_SUCCESS)
      karst_json_string(fp, hash);
    else
      fputs("null", fp);
    fprintf(fp, ", \"ncols\": %lld, \"nrows\": %lld, \"cellsize\": ", (long long)tr->ncols,
            (long long)tr->nrows);
    json_num(fp, tr->cellsize);
    fputs(", \"xllcorner\": ", fp), json_num(fp, tr->xll - 0.5 * tr->cellsize);
    fputs(", \"yllcorner\": ", fp), json_num(fp, tr->yll - 0.5 * tr->cellsize);
    fputs(", \"xllcenter\": ", fp), json_num(fp, tr->xll);
    fputs(", \"yllcenter\": ", fp), json_num(fp, tr->yll);
  } else {
    fputs("\"elevation\": ", fp), json_num(fp, sc->terrain.elevation);
  }
  fputs("},\n", fp);
  fputs("    \"water_table\": ", fp), surface_json(fp, &sc->water_table), fputs(",\n", fp);
  fputs("    \"horizons\": [", fp);
  for (int i = 0; i < sc->n_horizons; i++) {
    const karst_horizon_t *h = &sc->horizons[i];
    fputs(i ? ", {" : "{", fp);
    fputs("\"name\": ", fp), karst_json_string(fp, h->name);
    if (h->path) fputs(", ", fp), file_json(fp, "surface", h->path);
    fputs(", \"elevation\": ", fp), json_num(fp, h->elevation);
    fputs(", \"dip\": ", fp), json_num(fp, h->dip);
    fputs(", \"dip_direction\": ", fp), json_num(fp, h->dip_direction);
    fputs(", \"origin\": [", fp), json_num(fp, h->origin[0]), fputs(", ", fp),
        json_num(fp, h->origin[1]);
    fputs("], \"radius\": ", fp), json_num(fp, h->radius);
    fputc('}', fp);
  }
  fputs("],\n    \"fractures\": [", fp);
  for (int i = 0; i < sc->n_fractures; i++) {
    const karst_fracture_t *fr = &sc->fractures[i];
    fputs(i ? ", {" : "{", fp);
    fputs("\"dip_direction\": ", fp), json_num(fp, fr->dip_direction);
    fputs(", \"dip\": ", fp), json_num(fp, fr->dip);
    fputs(", \"weight\": ", fp), json_num(fp, fr->weight);
    fputs(", \"fisher_kappa\": ", fp), json_num(fp, fr->kappa > 0 ? fr->kappa : NAN);
    if (fr->dfn) {
      fputs(", \"dfn\": {\"p32\": ", fp), json_num(fp, fr->p32);
      fputs(", \"size_exponent\": ", fp), json_num(fp, fr->size_exponent);
      fputs(", \"r_min\": ", fp), json_num(fp, fr->r_min);
      fputs(", \"r_max\": ", fp), json_num(fp, fr->r_max);
      fputs(", \"factor\": ", fp), json_num(fp, fr->factor);
      fputs(", \"influence\": ", fp), json_num(fp, fr->influence);
      fputc('}', fp);
    } else {
      fputs(", \"dfn\": null", fp);
    }
    fputc('}', fp);
  }
  fputs("],\n    \"strata\": [", fp);
  for (int i = 0; i < sc->n_strata; i++) {
    const karst_stratum_t *st = &sc->strata[i];
    fputs(i ? ", {\"name\": " : "{\"name\": ", fp);
    karst_json_string(fp, st->name);
    fputs(", \"top\": ", fp), surface_json(fp, &st->top);
    fputs(", \"bottom\": ", fp), surface_json(fp, &st->bottom);
    fprintf(fp, ", \"soluble\": %s}", st->soluble ? "true" : "false");
  }
  fputs("],\n    \"exclusions\": [", fp);
  for (int i = 0; i < sc->n_exclusions; i++) {
    const karst_exclusion_t *e = &sc->exclusions[i];
    fputs(i ? ", {\"name\": " : "{\"name\": ", fp);
    karst_json_string(fp, e->name);
    if (e->kind == KARST_EXCLUSION_BOX) {
      fputs(", \"box\": {\"min\": ", fp), vec3(fp, e->min);
      fputs(", \"max\": ", fp), vec3(fp, e->max), fputc('}', fp);
    } else if (e->kind == KARST_EXCLUSION_SPHERE) {
      fputs(", \"sphere\": {\"center\": ", fp), vec3(fp, e->center);
      fputs(", \"radius\": ", fp), json_num(fp, e->radius), fputc('}', fp);
    } else {
      fputs(", \"prism\": {\"polygon\": [", fp);
      for (int v = 0; v < e->n_vertices; v++) {
        fputs(v ? ", [" : "[", fp), json_num(fp, e->polygon[2 * v]), fputs(", ", fp);
        json_num(fp, e->polygon[2 * v + 1]), fputc(']', fp);
      }
      fputs("], \"bottom\": ", fp), json_num(fp, e->bottom);
      fputs(", \"top\": ", fp), json_num(fp, e->top), fputc('}', fp);
    }
    fputc('}', fp);
  }
  fputs("],\n    \"faults\": [", fp);
  for (int i = 0; i < sc->n_faults; i++) {
    const karst_fault_t *f = &sc->faults[i];
    fputs(i ? ", {\"name\": " : "{\"name\": ", fp);
    karst_json_string(fp, f->name);
    fputs(", \"center\": ", fp), vec3(fp, f->center);
    fputs(", \"dip_direction\": ", fp), json_num(fp, f->dip_direction);
    fputs(", \"dip\": ", fp), json_num(fp, f->dip);
    fputs(", \"radius\": ", fp), json_num(fp, f->radius);
    fputs(", \"damage_zone\": ", fp), json_num(fp, f->damage_zone);
    fprintf(fp, ", \"kind\": \"%s\"", f->barrier ? "barrier" : "conduit");
    fputs(", \"factor\": ", fp), json_num(fp, f->factor);
    fputs(", \"crossing_cost\": ", fp), json_num(fp, f->crossing_cost);
    fputc('}', fp);
  }
  fputs("],\n    \"permeability\": {\"background\": ", fp);
  json_num(fp, sc->permeability.background);
  fputs(", \"tree\": ", fp);
  if (sc->permeability.root)
    perm_json(fp, sc->permeability.root);
  else
    fputs("null", fp);
  fputs("},\n    \"key_points\": [", fp);
  for (int i = 0; i < sc->n_key_points; i++) {
    const karst_keypoint_t *k = &sc->key_points[i];
    fputs(i ? ",\n      {\"name\": " : "\n      {\"name\": ", fp);
    karst_json_string(fp, k->name);
    fprintf(fp, ", \"type\": \"%s\", \"position\": ", keypoint_type(k->type));
    vec3(fp, k->p);
    /* Every key point has both members (null / [] when they do not apply), so the report shows
     * the key points as one table. */
    fputs(", \"water_table\": ", fp), surface_json(fp, &k->water_table);
    fputs(", \"drains_to\": [", fp);
    for (int j = 0; j < k->n_drains_to; j++) {
      if (j) fputs(", ", fp);
      karst_json_string(fp, sc->key_points[k->drains_to[j]].name);
    }
    fputc(']', fp);
    fputc('}', fp);
  }
  fputs("],\n    \"prescribed_paths\": [", fp);
  for (int i = 0; i < sc->n_prescribed; i++) {
    fputs(i ? ", [" : "[", fp);
    karst_json_string(fp, sc->key_points[sc->prescribed[i].a].name);
    fputs(", ", fp);
    karst_json_string(fp, sc->key_points[sc->prescribed[i].b].name);
    fputc(']', fp);
  }
  fputs("],\n    \"connectivity\": ", fp);
  if (sc->connectivity.given) {
    const karst_connectivity_t *c = &sc->connectivity;
    fputs("{\"sinks\": [", fp);
    for (int i = 0; i < c->n_sinks; i++) {
      if (i) fputs(", ", fp);
      karst_json_string(fp, sc->key_points[c->sinks[i]].name);
    }
    fputs("], \"springs\": [", fp);
    for (int j = 0; j < c->n_springs; j++) {
      if (j) fputs(", ", fp);
      karst_json_string(fp, sc->key_points[c->springs[j]].name);
    }
    fputs("], \"matrix\": [", fp);
    for (int i = 0; i < c->n_sinks; i++) {
      fputs(i ? ", [" : "[", fp);
      for (int j = 0; j < c->n_springs; j++)
        fprintf(fp, "%s%d", j ? ", " : "", c->matrix[i * c->n_springs + j]);
      fputc(']', fp);
    }
    fputs("]}", fp);
  } else {
    fputs("null", fp);
  }
  fputs(",\n    \"routing\": {\"vadose_factor\": ", fp);
  json_num(fp, sc->routing.vadose_factor);
  fputs(", \"rise_cost\": ", fp), json_num(fp, sc->routing.rise_cost);
  fputs(", \"phreatic_depth\": ", fp), json_num(fp, sc->routing.phreatic_depth);
  fputs(", \"water_table_band\": ", fp), json_num(fp, sc->routing.water_table_band);
  fputs("},\n    \"cost\": {\"w0\": ", fp);
  json_num(fp, sc->cost.w0);
  fputs(", \"horizon\": ", fp), json_num(fp, sc->cost.horizon);
  fputs(", \"fracture\": ", fp), json_num(fp, sc->cost.fracture);
  fputs(", \"permeability\": ", fp), json_num(fp, sc->cost.permeability);
  fputs(", \"prescribed\": ", fp), json_num(fp, sc->cost.prescribed);
  fprintf(fp, ", \"fracture_combine\": \"%s\"",
          sc->cost.fracture_combine == KARST_FRACTURE_MIN ? "min" : "sum");
  fputs("},\n    \"sampling\": {\"fill_radius\": ", fp);
  json_num(fp, sc->sampling.fill_radius);
  fputs(", \"feature_radius\": ", fp), json_num(fp, sc->sampling.feature_radius);
  fputs(", \"permeable_threshold\": ", fp), json_num(fp, sc->sampling.permeable_threshold);
  fputs(", \"feature_band\": ", fp), json_num(fp, sc->sampling.feature_band);
  fprintf(fp, ", \"k\": %d, \"knn\": \"%s\", \"max_samples\": %lld, ", sc->sampling.k,
          sc->sampling.knn == KARST_KNN_FLANN ? "flann" : "grid",
          (long long)sc->sampling.max_samples);
  char refine[64];
  karst_refine_names(sc->sampling.refine, "\", \"", refine, sizeof refine);
  fprintf(fp, "\"refine\": [%s%s%s], ", refine[0] ? "\"" : "", refine, refine[0] ? "\"" : "");
  file_json(fp, "points", sc->sampling.points);
  fprintf(fp, ", \"points_count\": %lld},\n", (long long)sc->sampling.n_points);
  kv_num(fp, I, "gamma", sc->gamma, 0);
  kv_num(fp, I, "reuse", sc->reuse, 0);
  kv_num(fp, I, "tortuosity", sc->tortuosity, 0);
  karst_amplification_options_t ao;
  karst_amplification_options_init(&ao);
  fprintf(fp, "    \"amplification\": {\"steps\": %d, \"points\": %d, \"dead_end_fraction\": ",
          sc->amplification.steps, sc->amplification.points);
  json_num(fp, sc->amplification.dead_end_fraction);
  fputs(", \"reach\": ", fp), json_num(fp, sc->amplification.reach);
  fputs(", \"reach_ratio\": ", fp), json_num(fp, sc->amplification.reach_ratio);
  fputs(", \"points_ratio\": ", fp), json_num(fp, sc->amplification.points_ratio);
  fprintf(fp, ", \"anchor\": \"%s\"",
          sc->amplification.anchor == KARST_ANCHOR_NETWORK ? "network" : "previous");
  fputs(", \"displacement_ratio\": ", fp),
      json_num(fp, karst_amplification_displacement_ratio(&ao, sc->tortuosity));
  fputs(", \"ratio_at_theta1\": ", fp), json_num(fp, ao.ratio_at_theta1);
  fputs(", \"min_segment\": ", fp), json_num(fp, ao.min_segment);
  fprintf(fp, ", \"max_levels\": %d, \"max_tries\": %d, \"loop_separation\": ", ao.max_levels,
          ao.max_tries);
  json_num(fp, ao.loop_separation);
  fputs("},\n    \"classification\": {\"vertical_angle\": ", fp);
  json_num(fp, sc->classification.vertical_angle);
  fputs(", \"epikarst_depth\": ", fp), json_num(fp, sc->classification.epikarst_depth);
  fputs(", \"chamber_resistance\": ", fp), json_num(fp, sc->classification.chamber_resistance);
  fputs(", \"radius_correlation\": ", fp), json_num(fp, sc->classification.radius_correlation);
  fprintf(fp, ", \"radius_field_waves\": %d", KARST_CLASSIFICATION_RADIUS_WAVES);
  fputs(", \"radius\": {", fp);
  for (int t = 0; t < KARST_TUNNEL_TYPE_COUNT; t++) {
    fprintf(fp, "%s\"%s\": [", t ? ", " : "", karst_tunnel_type_name((karst_tunnel_type_t)t));
    json_num(fp, sc->classification.radius[t].min);
    fputs(", ", fp);
    json_num(fp, sc->classification.radius[t].max);
    fputc(']', fp);
  }
  fputs("}},\n", fp);
  frame_json(fp, sc);
}

/**
 * Write run.json for one realisation, atomically: karst version and those of
 * the libraries (karst_versions_json), scenario
 * path and FNV-1a hash (karst_file_hash; null when built in code), seed and
 * realisation, every effective parameter of @p sc and of the amplification
 * constants, the counts and the wall time of each stage of @p stats.
 * Timings appear only here, so the other outputs of a seed are byte-identical.
 *
 * @return KARST_SUCCESS, KARST_EIO (message names the file), KARST_ENOMEM.
 * Time complexity: O(size of the scenario).
 */
karst_error_t karst_generate_write_run(karst_ctx_t *ctx, const char *path,
                                       const karst_scenario_t *sc, uint64_t seed,
                                       uint64_t realisation, const karst_generate_stats_t *st) {
  char hash[17] = "";
  karst_error_t err;
  if (sc->path && (err = karst_file_hash(ctx, sc->path, hash))) return err;
  char *versions = karst_versions_json();
  if (!versions) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  karst_atomic_file_t f;
  if ((err = karst_atomic_open(ctx, &f, path, "w"))) {
    free(versions);
    return err;
  }
  FILE *fp = f.fp;
  const char *I = "    ";
  fputs("{\n  \"karst_version\": ", fp);
  karst_json_string(fp, karst_version());
  fprintf(fp, ",\n  \"versions\": %s", versions);
  fputs(",\n  \"scenario\": ", fp);
  if (sc->path)
    karst_json_string(fp, sc->path);
  else
    fputs("null", fp);
  fputs(",\n  \"scenario_hash\": ", fp);
  if (sc->path)
    karst_json_string(fp, hash);
  else
    fputs("null", fp);
  fprintf(fp, ",\n  \"seed\": %llu,\n  \"realisation\": %llu,\n", (unsigned long long)seed,
          (unsigned long long)realisation);
  fputs("  \"parameters\": {\n", fp);
  karst_generate_write_parameters(fp, sc);
  fputs("  },\n  \"counts\": {\n", fp);
  fprintf(fp, "    \"samples\": %lld,\n    \"graph_edges\": %lld,\n    \"key_points\": %lld,\n",
          (long long)st->n_samples, (long long)st->n_graph_edges, (long long)st->n_key_points);
  fprintf(
      fp,
      "    \"skeleton_paths\": %lld,\n    \"network_nodes\": %lld,\n    \"network_edges\": %lld,\n",
      (long long)st->n_skeleton_paths, (long long)st->n_nodes, (long long)st->n_edges);
  fprintf(fp, "    \"points_kept\": %lld,\n", (long long)st->n_points_kept);
  fprintf(fp, "    \"skeleton_nodes\": %lld,\n", (long long)st->n_skeleton_nodes);
  kv_num(fp, I, "skeleton_length", st->skeleton_length, 0);
  fprintf(fp, "    \"observed_edges\": %lld,\n", (long long)st->n_observed_edges);
  kv_num(fp, I, "observed_length", st->observed_length, 0);
  kv_num(fp, I, "total_length", st->total_length, 1);
  fputs("  },\n  \"generations\": [", fp);
  for (int g = 0; g < st->n_generations && g < KARST_SCENARIO_MAX_GENERATIONS; g++) {
    const karst_generation_stats_t *gs = &st->generations[g];
    fprintf(fp, "%s{\"generation\": %d, \"name\": ", g ? ",\n    " : "\n    ", g + 1);
    if (g < sc->n_generations)
      karst_json_string(fp, sc->generations[g].name);
    else
      fputs("null", fp);
    fprintf(fp,
            ", \"routes\": %lld, \"new_edges\": %lld, \"new_length\": ", (long long)gs->n_routes,
            (long long)gs->n_new_edges);
    json_num(fp, gs->new_length);
    fputs(", \"reactivated_length\": ", fp);
    json_num(fp, gs->reactivated_length);
    fputc('}', fp);
  }
  fputs(st->n_generations > 0 ? "\n  ],\n  \"crs\": " : "],\n  \"crs\": ", fp);
  if (sc->crs)
    karst_json_string(fp, sc->crs);
  else
    fputs("null", fp);
  fputs(",\n  \"stage_seconds\": {\n", fp);
  for (int s = 0; s < KARST_STAGE_COUNT; s++)
    kv_num(fp, I, karst_stage_name(s), st->stage_seconds[s], s == KARST_STAGE_COUNT - 1);
  fprintf(fp, "  },\n  \"peak_bytes\": %zu\n}\n", st->peak_bytes);
  free(versions);
  return karst_atomic_commit(ctx, &f);
}
