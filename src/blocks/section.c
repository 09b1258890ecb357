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

/** Release the section (NULL allowed). O(strata). */
void karst_blocks_section_free(karst_blocks_section_t *b) {
  if (!b) return;
  for (int i = 0; i < b->n_strata; i++)
    free(b->strata[i].name);
  free(b->strata);
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
  double k = b->tile_size / par->size; /* disc sizes scale with the tile */
  par->size = b->tile_size;
  par->disc_spacing *= k;
  par->disc_radius_min *= k;
  par->disc_radius_max *= k;
  par->bedding_spacing *= k;
  par->poisson_radius = b->poisson_radius;
  par->graph_radius = b->graph_radius > 0 ? b->graph_radius : 2 * b->poisson_radius;
  par->hull_margin = b->hull_margin > 0 ? b->hull_margin : par->graph_radius;
  par->degenerate_radius = b->poisson_radius;
  par->smooth_radius = b->smooth_radius;
  par->aperture = b->aperture;
  par->seed = seed;
  par->warp.relief = (karst_blocks_relief_kind_t)b->warp_relief;
  par->warp.amplitude = b->warp_amplitude;
  par->warp.wavelength = b->warp_wavelength;
  par->warp.image = b->warp_image;
}
