/* The blocks section of a scenario as the library sees it: defaults, the
 * elevation-band strata (the stratum callback until the geology module
 * provides named strata), and the tile parameters it implies. The YAML
 * schema is in src/scenario/scenario_blocks.inc. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "karst/blocks.h"

/** Defaults of the blocks section (docs/blocks.md). O(1). */
void karst_blocks_section_init(karst_blocks_section_t *b) {
  memset(b, 0, sizeof *b);
  karst_blocks_tile_params_t p;
  karst_blocks_tile_params_init(&p, KARST_BLOCK_EQUIDIMENSIONAL);
  b->tile_size = p.size;
  b->poisson_radius = p.poisson_radius;
  b->graph_radius = 0; /* 2 r */
  b->smooth_radius = p.smooth_radius;
  b->aperture = p.aperture;
  b->hull_margin = 0; /* the graph radius */
  b->voxel = 0.5;
  b->tile_voxel = 0.25;
  karst_blocks_presence_init(&b->presence);
  b->warp_relief = KARST_BLOCKS_RELIEF_NONE;
  b->warp_amplitude = p.warp.amplitude;
  b->warp_wavelength = p.warp.wavelength;
}

static void shape_free(karst_blocks_shape_t *s) {
  for (int i = 0; i < s->n_children; i++)
    shape_free(&s->children[i]);
  free(s->children);
}

/** Release the section (NULL allowed). O(strata + authored nodes). */
void karst_blocks_section_free(karst_blocks_section_t *b) {
  if (!b) return;
  for (int i = 0; i < b->n_strata; i++)
    free(b->strata[i].name);
  free(b->strata);
  for (int i = 0; i < b->n_authored; i++)
    shape_free(&b->authored[i].shape);
  free(b->authored);
  free(b->user_discs);
  free(b->warp_image);
  free(b);
}

/**
 * Stratum of @p p by elevation band: the first stratum whose `below` lies
 * above p_z (strata are listed from the bottom up; the last may have no
 * bound). -1 above every band. O(strata).
 */
int karst_blocks_section_stratum(void *arg, const double p[3]) {
  const karst_blocks_section_t *b = arg;
  for (int i = 0; i < b->n_strata; i++)
    if (p[2] < b->strata[i].below) return i;
  return -1;
}

/** Tile parameters of @p type with the section's shared values. O(1). */
void karst_blocks_section_tile_params(const karst_blocks_section_t *b, int type, uint64_t seed,
                                      karst_blocks_tile_params_t *par) {
  karst_blocks_tile_params_init(par, type);
  karst_blocks_tile_params_resize(par, b->tile_size, b->poisson_radius);
  if (b->graph_radius > 0) par->graph_radius = b->graph_radius;
  par->hull_margin = b->hull_margin > 0 ? b->hull_margin : par->graph_radius;
  par->smooth_radius = b->smooth_radius;
  par->aperture = b->aperture;
  par->seed = seed;
  par->warp.relief = (karst_blocks_relief_kind_t)b->warp_relief;
  par->warp.amplitude = b->warp_amplitude;
  par->warp.wavelength = b->warp_wavelength;
  par->warp.image = b->warp_image;
}

/** The user's discs of tile @p type, in the order of blocks.user_discs. O(discs). */
int karst_blocks_section_user_discs(const karst_blocks_section_t *b, int type,
                                    karst_blocks_disc_t *discs) {
  int n = 0;
  for (int i = 0; i < b->n_user_discs; i++)
    if (b->user_discs[i].tile == type) discs[n++] = b->user_discs[i].disc;
  return n;
}

/** Bounding box of an authored node: union, intersection or first child of its children's. */
void karst_blocks_shape_box(const karst_blocks_shape_t *s, double box[6]) {
  switch (s->kind) {
  case KARST_BLOCKS_SHAPE_SPHERE:
    for (int a = 0; a < 3; a++)
      box[a] = s->a[a] - s->radius, box[a + 3] = s->a[a] + s->radius;
    return;
  case KARST_BLOCKS_SHAPE_BOX:
    for (int a = 0; a < 3; a++)
      box[a] = s->a[a], box[a + 3] = s->b[a];
    return;
  default:
    break;
  }
  karst_blocks_shape_box(&s->children[0], box);
  for (int i = 1; i < s->n_children && s->kind != KARST_BLOCKS_SHAPE_DIFFERENCE; i++) {
    double c[6];
    karst_blocks_shape_box(&s->children[i], c);
    for (int a = 0; a < 3; a++)
      if (s->kind == KARST_BLOCKS_SHAPE_UNION)
        box[a] = fmin(box[a], c[a]), box[a + 3] = fmax(box[a + 3], c[a + 3]);
      else
        box[a] = fmax(box[a], c[a]), box[a + 3] = fmin(box[a + 3], c[a + 3]);
  }
}

/* One authored node into @p tree (children first). */
static karst_error_t shape_build(karst_ctx_t *ctx, const karst_blocks_shape_t *s, karst_sdf_t *tree,
                                 karst_int_t *node) {
  switch (s->kind) {
  case KARST_BLOCKS_SHAPE_SPHERE:
    return karst_sdf_sphere(ctx, tree, s->a, s->radius, 0, node);
  case KARST_BLOCKS_SHAPE_BOX:
    return karst_sdf_box(ctx, tree, s->a, s->b, node);
  default:
    break;
  }
  karst_int_t *kids = malloc((size_t)s->n_children * sizeof *kids);
  if (!kids) return karst_set_error(ctx, KARST_ENOMEM, "blocks: out of memory");
  karst_error_t err = KARST_SUCCESS;
  for (int i = 0; i < s->n_children && !err; i++)
    err = shape_build(ctx, &s->children[i], tree, &kids[i]);
  if (!err && s->kind == KARST_BLOCKS_SHAPE_UNION) {
    err = karst_sdf_union(ctx, tree, s->n_children, kids, node);
  } else if (!err) { /* intersection, or the first child minus the others, pair by pair */
    *node = kids[0];
    for (int i = 1; i < s->n_children && !err; i++)
      err = s->kind == KARST_BLOCKS_SHAPE_INTERSECTION
                ? karst_sdf_intersection(ctx, tree, *node, kids[i], node)
                : karst_sdf_difference(ctx, tree, *node, kids[i], node);
  }
  free(kids);
  return err;
}

karst_error_t karst_blocks_section_authored(karst_ctx_t *ctx, const karst_blocks_section_t *b,
                                            int type, karst_sdf_t *tree, karst_int_t *nodes,
                                            int *n) {
  *n = 0;
  for (int i = 0; i < b->n_authored; i++) {
    if (b->authored[i].tile != type) continue;
    karst_error_t err = shape_build(ctx, &b->authored[i].shape, tree, &nodes[*n]);
    if (err) return err;
    (*n)++;
  }
  return KARST_SUCCESS;
}
