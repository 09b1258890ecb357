/* Builds the small demonstration network of docs/geometry_demo.png and writes its mesh (voxel
 * 0.12 m; the default walls: blended junctions, sections changing along the edges, wall details
 * and speleothems; with a second argument also the solid noise of 0.5 m) to argv[1] (.vtp for
 * the picture) with the ParaView script beside it; see docs/geometry.md. */
#include "karst.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
int main(int argc, char **argv) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = 2;
  karst_network_t net;
  karst_network_init(&net);
  double P[][3] = {{0, 0, 0},   {14, 2, 0.5}, {26, -3, 1},  {36, 4, 0},  {44, 14, -1}, {40, 26, 0},
                   {28, 30, 1}, {16, 26, 0},  {6, 16, 0.5}, {0, 0, 0},   {26, -3, 1},  {26, -3, 14},
                   {40, 26, 0}, {58, 34, -2}, {36, 4, 0},   {52, -4, -1}};
  int n = sizeof P / sizeof P[0];
  for (int i = 0; i < n; i++)
    karst_network_add_node(&net, P[i][0], P[i][1], P[i][2], NULL);
  int E[][3] = {
      {0, 1, KARST_TUNNEL_TUBE},      {1, 2, KARST_TUNNEL_TUBE},     {2, 3, KARST_TUNNEL_KEYHOLE},
      {3, 4, KARST_TUNNEL_KEYHOLE},   {4, 5, KARST_TUNNEL_CANYON},   {5, 6, KARST_TUNNEL_PASSAGE},
      {6, 7, KARST_TUNNEL_PASSAGE},   {7, 8, KARST_TUNNEL_BED},      {8, 0, KARST_TUNNEL_BED},
      {2, 11, KARST_TUNNEL_EPIKARST}, {5, 13, KARST_TUNNEL_CHAMBER}, {3, 15, KARST_TUNNEL_CANYON}};
  int ne = sizeof E / sizeof E[0];
  double *rad, *typ;
  for (int e = 0; e < ne; e++)
    karst_network_add_edge(&net, E[e][0], E[e][1], NULL);
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "radius", 1, 0, &rad);
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &typ);
  for (int e = 0; e < ne; e++) {
    typ[e] = E[e][2];
    rad[e] = E[e][2] == KARST_TUNNEL_EPIKARST ? 0.6 : 1.6;
  }
  rad[10] = 4;
  karst_implicit_params_t par;
  karst_implicit_params_init(&par);
  par.noise_amplitude = argc > 2 ? 0.5 : 0;
  par.noise_wavelength = 1.5;
  par.voxel = 0.12;
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  karst_implicit_stats_t st;
  if (karst_implicit_build(&ctx, &net, &par, NULL, t, &st)) {
    fprintf(stderr, "%s\n", ctx.errmsg);
    return 1;
  }
  double box[6];
  karst_sdf_node_box(t, karst_sdf_root(t), box);
  for (int a = 0; a < 3; a++)
    box[a] -= 0.5, box[a + 3] += 0.5;
  karst_mesh_t m;
  karst_mesh_init(&m);
  if (karst_mesh_polygonize(&ctx, t, box, 0.12, &m, NULL)) {
    fprintf(stderr, "%s\n", ctx.errmsg);
    return 1;
  }
  if (karst_mesh_write(&ctx, argv[1], &m)) {
    fprintf(stderr, "%s\n", ctx.errmsg);
    return 1;
  }
  /* The ParaView script beside it, as karst mesh writes one: its palette colours the picture. */
  char *script = karst_view_script_path(argv[1]);
  karst_view_item_t item = {argv[1], KARST_VIEW_MESH, NULL};
  if (!script || karst_view_write_script(&ctx, script, script, &item, 1)) {
    fprintf(stderr, "%s\n", ctx.errmsg);
    return 1;
  }
  free(script);
  printf("%lld triangles, %lld spheres, %lld bends, %lld mitred ends, %lld morphing sweeps, %lld "
         "blended junctions, %lld stalactites, %lld stalagmites\n",
         (long long)m.n_triangles, (long long)st.n_spheres, (long long)st.n_bends,
         (long long)st.n_mitred_ends, (long long)st.n_morphs, (long long)st.n_blends,
         (long long)st.n_stalactites, (long long)st.n_stalagmites);
  return 0;
}
