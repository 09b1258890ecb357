/* karst mesh: polygonize the conduits of a network (or the terrain carved by
 * them) into a closed triangle mesh; the geometry lives in src/implicit/ and
 * src/mesh/, this file only reads arguments and files. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

#include "cli.h"
#include "karst/blocks.h"

static const char *ext_of(const char *path) {
  const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
  return dot && (!slash || dot > slash) ? dot : "";
}

static int parse_box(const char *s, double box[6]) {
  char *end;
  const char *p = s;
  for (int i = 0; i < 6; i++) {
    box[i] = strtod(p, &end);
    if (end == p || !isfinite(box[i])) return -1;
    if (i < 5) {
      if (*end != ',') return -1;
      p = end + 1;
    } else if (*end != '\0') {
      return -1;
    }
  }
  for (int a = 0; a < 3; a++)
    if (!(box[a] < box[a + 3])) return -1;
  return 0;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static double grid_points(const karst_int_t c[3]) {
  return (double)(c[0] + 1) * (double)(c[1] + 1) * (double)(c[2] + 1);
}

/* The region meshed at @p voxel: @p base widened by @p margin voxels. */
static void widen(const double base[6], double margin, double voxel, double box[6]) {
  for (int a = 0; a < 3; a++)
    box[a] = base[a] - margin * voxel, box[a + 3] = base[a + 3] + margin * voxel;
}

/* --sdf samples every grid point (KARST_MESH_SAMPLE_MAX at most): say so
 * before the polygonization rather than after it, with the smallest voxel,
 * in two significant digits, that would fit (the default box grows with the
 * voxel: @p base plus @p margin voxels). */
static karst_error_t check_sdf_size(karst_ctx_t *ctx, const char *path, const double base[6],
                                    double margin, double voxel) {
  karst_int_t c[3];
  double box[6];
  widen(base, margin, voxel, box);
  karst_error_t err = karst_mesh_grid(ctx, box, voxel, c);
  if (err) return err;
  double pts = grid_points(c), lim = (double)KARST_MESH_SAMPLE_MAX;
  if (pts <= lim) return KARST_SUCCESS;
  double v = voxel * cbrt(pts / lim), p10 = pow(10, floor(log10(v)) - 1);
  v = ceil(v / p10) * p10;
  int found = 0;
  for (int i = 0; i < 1000 && !found; i++, v += p10) {
    karst_int_t d[3];
    widen(base, margin, v, box);
    found = karst_mesh_grid(NULL, box, v, d) == KARST_SUCCESS && grid_points(d) <= lim;
  }
  if (!found) /* the box is too thin for any voxel that would fit: only a smaller box helps */
    return karst_set_error(ctx, KARST_ERANGE,
                           "--sdf %s: the grid of %lld x %lld x %lld cells (%.0f points at "
                           "--voxel %g) exceeds the limit of %.0f points (2^28), and no coarser "
                           "voxel fits this box; use a smaller --box",
                           path, (long long)c[0], (long long)c[1], (long long)c[2], pts, voxel,
                           lim);
  v -= p10; /* the loop stepped past the voxel that fits */
  return karst_set_error(ctx, KARST_ERANGE,
                         "--sdf %s: the grid of %lld x %lld x %lld cells (%.0f points at --voxel "
                         "%g) exceeds the limit of %.0f points (2^28); use --voxel %g or larger, "
                         "or a smaller --box",
                         path, (long long)c[0], (long long)c[1], (long long)c[2], pts, voxel, lim,
                         v);
}

static int run(int argc, char **argv) {
  const char *in = NULL, *out = NULL, *scen_path = NULL, *sdf_path = NULL;
  double voxel = 0.5, box[6], blend = NAN;
  int have_box = 0, carve = 0, quiet = 0, threads = 0, have_seed = 0, blocks = 0;
  karst_implicit_params_t par;
  karst_implicit_params_init(&par);
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int more = i + 1 < argc;
    if (cli_is_help(a)) {
      cli_print_help(cli_find_command("mesh"));
      return CLI_OK;
    } else if (strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) {
      if (!more) return cli_usage_error("mesh", "%s needs a file name", a);
      out = argv[++i];
    } else if (strcmp(a, "--voxel") == 0) {
      if (!more || cli_parse_double(argv[i + 1], &voxel) || !(voxel > 0))
        return cli_usage_error("mesh", "--voxel needs a size > 0 in metres, got '%s'",
                               more ? argv[i + 1] : "");
      i++;
    } else if (strcmp(a, "--box") == 0) {
      if (!more || parse_box(argv[i + 1], box))
        return cli_usage_error("mesh",
                               "--box needs x0,y0,z0,x1,y1,z1 with x0 < x1, y0 < y1, z0 < z1, "
                               "got '%s'",
                               more ? argv[i + 1] : "");
      have_box = 1;
      i++;
    } else if (strcmp(a, "--spheres") == 0) {
      par.bend_spheres = 1;
    } else if (strcmp(a, "--blend") == 0) {
      if (!more || cli_parse_double(argv[i + 1], &blend) || !(blend >= 0))
        return cli_usage_error("mesh",
                               "--blend needs a width >= 0 in metres (0: hard union), got '%s'",
                               more ? argv[i + 1] : "");
      i++;
    } else if (strcmp(a, "--no-details") == 0) {
      par.details = 0;
    } else if (strcmp(a, "--no-speleothems") == 0) {
      par.speleothems = 0;
    } else if (strcmp(a, "--realisation") == 0) {
      if (!more || cli_parse_u64(argv[i + 1], &par.realisation))
        return cli_usage_error("mesh",
                               "--realisation must be an integer from 0 to 18446744073709551615, "
                               "got '%s'",
                               more ? argv[i + 1] : "");
      i++;
    } else if (strcmp(a, "--carve") == 0) {
      carve = 1;
    } else if (strcmp(a, "--blocks") == 0) {
      blocks = 1;
    } else if (strcmp(a, "--scenario") == 0) {
      if (!more) return cli_usage_error("mesh", "--scenario needs a file name");
      scen_path = argv[++i];
    } else if (strcmp(a, "--sdf") == 0) {
      if (!more) return cli_usage_error("mesh", "--sdf needs a file name");
      sdf_path = argv[++i];
    } else if (strcmp(a, "--noise") == 0) {
      if (!more || cli_parse_double(argv[i + 1], &par.noise_amplitude) ||
          !(par.noise_amplitude >= 0))
        return cli_usage_error("mesh", "--noise needs an amplitude >= 0 in metres, got '%s'",
                               more ? argv[i + 1] : "");
      i++;
    } else if (strcmp(a, "--radius") == 0) {
      if (!more || cli_parse_double(argv[i + 1], &par.default_radius) || !(par.default_radius > 0))
        return cli_usage_error("mesh", "--radius needs a radius > 0 in metres, got '%s'",
                               more ? argv[i + 1] : "");
      i++;
    } else if (strcmp(a, "--seed") == 0) {
      if (!more || cli_parse_u64(argv[i + 1], &par.seed))
        return cli_usage_error("mesh",
                               "--seed must be an integer from 0 to 18446744073709551615, got '%s'",
                               more ? argv[i + 1] : "");
      have_seed = 1;
      i++;
    } else if (strcmp(a, "-j") == 0 || strcmp(a, "--threads") == 0) {
      if (!more || cli_parse_int(argv[i + 1], &threads) || threads < 1 ||
          threads > KARST_ENSEMBLE_MAX_THREADS)
        return cli_usage_error("mesh",
                               "%s must be a whole number of threads within [1, %d], got '%s'", a,
                               KARST_ENSEMBLE_MAX_THREADS, more ? argv[i + 1] : "");
      i++;
    } else if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
      quiet = 1;
    } else if (a[0] == '-' && a[1] != '\0') {
      return cli_usage_error("mesh", "unknown option '%s'", a);
    } else if (!in) {
      in = a;
    } else {
      return cli_usage_error("mesh", "more than one network given ('%s' and '%s')", in, a);
    }
  }
  if (!in) return cli_usage_error("mesh", "no network file given");
  if (!out) return cli_usage_error("mesh", "no output file given (-o cave.vtp|.ply|.stl)");
  const char *ext = ext_of(out);
  if (strcasecmp(ext, ".vtp") && strcasecmp(ext, ".ply") && strcasecmp(ext, ".stl"))
    return cli_usage_error("mesh", "output '%s': the extension must be .vtp, .ply or .stl", out);
  if (sdf_path && strcasecmp(ext_of(sdf_path), ".vti"))
    return cli_usage_error("mesh", "--sdf '%s': the extension must be .vti", sdf_path);
  if (carve && !scen_path)
    return cli_usage_error("mesh", "--carve needs --scenario (the terrain comes from it)");
  if (blocks && !carve)
    return cli_usage_error("mesh", "--blocks needs --carve (the blocks amplify the terrain)");

  {
    const char *inputs[2] = {in, scen_path};
    const char *outputs[2] = {out, sdf_path};
    for (int o = 0; o < 2; o++) {
      int st = cli_refuse_output_over_input("mesh", outputs[o], inputs, 2);
      if (st) return st;
    }
  }
  karst_ctx_t ctx;
  cli_ctx_init(&ctx, quiet, 0);
  if (threads > 0) ctx.nthreads = threads;
  karst_network_t net;
  karst_network_init(&net);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_sdf_t *sdf = NULL;
  karst_blocks_amplified_t *amp = NULL;
  karst_mesh_t mesh;
  karst_mesh_init(&mesh);
  karst_fileset_t outs;
  karst_fileset_init(&outs);
  int status = CLI_OK;
  karst_error_t err;
  /* every output is checked before any work, written to a temporary, and
   * renamed into place only when all of them were written */
  const char *tmp_out = NULL, *tmp_sdf = NULL, *tmp_script = NULL, *writing = NULL;
  char *script = karst_view_script_path(out);
  if (!script) {
    err = karst_set_error(&ctx, KARST_ENOMEM, "out of memory");
    goto fail;
  }
  if (scen_path) { /* neither output may replace a file the scenario reads */
    char **sfiles = NULL;
    int nsf = 0, st = CLI_OK;
    if ((err = karst_scenario_files(&ctx, scen_path, &sfiles, &nsf))) goto fail;
    for (int o = 0; o < 2 && !st; o++)
      st = cli_refuse_output_over_input("mesh", o ? sdf_path : out, (const char *const *)sfiles,
                                        nsf);
    for (int k = 0; k < nsf; k++)
      free(sfiles[k]);
    free(sfiles);
    if (st) {
      status = st;
      goto done;
    }
  }
  if ((err = cli_add_output(&ctx, &outs, out, &tmp_out))) goto fail;
  if (sdf_path && (err = cli_add_output(&ctx, &outs, sdf_path, &tmp_sdf))) goto fail;
  if ((err = cli_add_output(&ctx, &outs, script, &tmp_script))) goto fail;
  double t0 = now_s();
  if ((err = karst_read_network(&ctx, in, KARST_FORMAT_AUTO, &net))) goto fail;
  if (scen_path && (err = karst_scenario_load(&ctx, scen_path, &sc))) goto fail;
  /* the scenario's geometry section (defaults without one), its seed and
   * fracture families; --blend overrides geometry.blend */
  if (scen_path && !have_seed) par.seed = sc.seed;
  if (!isnan(blend)) sc.geometry.blend = blend;
  par.geometry = &sc.geometry;
  par.fractures = sc.fractures;
  par.n_fractures = sc.n_fractures;
  par.voxel = voxel;
  if ((err = karst_sdf_create(&ctx, &sdf))) goto fail;
  karst_implicit_stats_t bst;
  if ((err = karst_implicit_build(&ctx, &net, &par, carve && !blocks ? &sc.terrain : NULL, sdf,
                                  &bst)))
    goto fail;
  if (blocks) { /* the conduits carved out of the block-amplified terrain (docs/blocks.md) */
    karst_int_t conduits = karst_sdf_root(sdf), rock, root;
    if ((err = karst_blocks_amplify(&ctx, &sc, sdf, &amp, &rock)) ||
        (err = karst_sdf_difference(&ctx, sdf, rock, conduits, &root)) ||
        (err = karst_sdf_set_root(&ctx, sdf, root)))
      goto fail;
  }
  double t1 = now_s();
  double base[6], margin = 0;
  if (have_box) {
    memcpy(base, box, sizeof base);
  } else if (scen_path) {
    for (int a = 0; a < 3; a++)
      base[a] = sc.domain_min[a], base[a + 3] = sc.domain_max[a];
  } else {
    /* the conduits' bounding box, two voxels of margin */
    karst_sdf_node_box(sdf, karst_sdf_root(sdf), base);
    margin = 2;
  }
  widen(base, margin, voxel, box);
  if (sdf_path && (err = check_sdf_size(&ctx, sdf_path, base, margin, voxel))) goto fail;
  karst_polygonize_stats_t pst;
  if ((err = karst_mesh_polygonize(&ctx, sdf, box, voxel, &mesh, &pst))) goto fail;
  if (blocks) /* labels: tunnel types, -1 on the terrain and its blocks */
    karst_blocks_relabel_mesh(&ctx, sdf, &mesh, NULL, NULL);
  double t2 = now_s();
  writing = out;
  if ((err = karst_mesh_write(&ctx, tmp_out, &mesh))) goto fail_write;
  writing = sdf_path;
  if (sdf_path && (err = karst_mesh_write_sdf(&ctx, tmp_sdf, sdf, box, voxel))) goto fail_write;
  writing = script;
  karst_view_item_t items[2] = {{out, KARST_VIEW_MESH, NULL}, {sdf_path, KARST_VIEW_FIELD, NULL}};
  if ((err = karst_view_write_script(&ctx, tmp_script, script, items, sdf_path ? 2 : 1)))
    goto fail_write;
  /* the writers do not poll the interrupt: a Ctrl-C while they ran keeps nothing */
  if (karst_interrupted(&ctx)) {
    err = karst_set_error(&ctx, KARST_EINTERRUPTED, "interrupted; no output was kept");
    goto fail;
  }
  if ((err = karst_fileset_commit(&ctx, &outs))) goto fail;
  if (strcasecmp(ext, ".stl") == 0) {
    /* float32 STL far from the origin: the vertices are shifted (mesh.h); the
     * user needs the shift to put the mesh back in place, even with --quiet */
    double o[3];
    karst_mesh_stl_origin(&mesh, o);
    if (o[0] != 0 || o[1] != 0 || o[2] != 0)
      fprintf(stderr,
              "karst mesh: %s: vertices are relative to the origin x=%.0f y=%.0f z=%.0f m "
              "(float32 STL; also in its header): add it to get the true coordinates\n",
              out, o[0], o[1], o[2]);
  }
  if (!quiet) {
    karst_sdf_stats_t ss;
    karst_sdf_stats(sdf, &ss);
    printf(
        "%s: %lld triangles, %lld vertices, voxel %g m, box %.10g,%.10g,%.10g,%.10g,%.10g,%.10g; "
        "tree of %lld nodes (%lld sweeps of which %lld morphing, %lld revolved, %lld spheres, "
        "%lld ellipsoids, %lld blended junctions, %lld stalactites, %lld stalagmites, %s; "
        "%.1f MB) built in %.2f s, polygonized in %.2f s on %d threads%s\n",
        out, (long long)mesh.n_triangles, (long long)mesh.n_vertices, voxel, box[0], box[1], box[2],
        box[3], box[4], box[5], (long long)ss.n_nodes, (long long)ss.by_kind[KARST_SDF_SWEEP],
        (long long)bst.n_morphs, (long long)ss.by_kind[KARST_SDF_REVOLVE],
        (long long)ss.by_kind[KARST_SDF_SPHERE], (long long)ss.by_kind[KARST_SDF_ELLIPSOID],
        (long long)bst.n_blends, (long long)bst.n_stalactites, (long long)bst.n_stalagmites,
        bst.details_lipschitz > 0 ? "wall details" : "smooth walls", ss.memory_bytes / 1e6, t1 - t0,
        t2 - t1, ctx.nthreads, blocks  ? ", block-amplified terrain carved"
        : carve ? ", terrain carved"
                : "");
  }
  goto done;
fail_write:
  cli_note_failed_output(&ctx, err, writing);
fail:
  status = cli_fail("mesh", &ctx, err);
done:
  free(script);
  karst_fileset_abort(&outs);
  karst_mesh_destroy(&mesh);
  karst_sdf_free(sdf);
  karst_blocks_amplified_free(amp);
  karst_scenario_destroy(&sc);
  karst_network_destroy(&net);
  return status;
}

const cli_command_t cli_cmd_mesh = {
    "mesh", run, "polygonize the conduits of a network into a closed triangle mesh",
    "usage: karst mesh NETWORK.vtp -o cave.vtp [--voxel 0.5] [--box x0,y0,z0,x1,y1,z1]\n"
    "                  [--scenario S.yaml [--carve [--blocks]]] [--blend R] [--no-details]\n"
    "                  [--no-speleothems] [--sdf cave.vti] [--noise A] [--radius R]\n"
    "                  [--spheres] [--seed S] [--realisation N] [-j THREADS] [--quiet]\n\n"
    "Builds the implicit geometry of the network's conduits (Paris et al. 2021, §6: one sweep\n"
    "of the tunnel type's cross-section per edge, scaled by its \"radius\" and interpolated along\n"
    "it between the sections at its ends, the sections revolved about the axis of sharp bends,\n"
    "ellipsoids for chambers, junctions blended; wall details of Zanni et al. 2012 and\n"
    "speleothems by the scenario's geometry section) and polygonizes it into a closed, manifold,\n"
    "consistently oriented triangle mesh labelled by tunnel type (-1: terrain or box) and feature\n"
    "(0 wall, 1 speleothem). NETWORK may also be\n"
    "any survey format karst reads (Karstnet, .pl, .sql, .3d, .svx): edges without a radius\n"
    "get --radius, edges without a tunnel type are tubes.\n\n"
    "  -o FILE        output mesh; .vtp (ParaView), .ply (binary) or .stl (binary) by extension;\n"
    "                 STL far from the origin is shifted by the origin printed and in its header\n"
    "  --voxel H      grid spacing in metres (default 0.5)\n"
    "  --box ...      region to mesh; the mesh is closed where the solid leaves it (default:\n"
    "                 the scenario's domain with --scenario, else the conduits plus 2 voxels)\n"
    "  --carve        mesh the rock: the scenario's terrain minus the conduits\n"
    "  --scenario S   scenario file: its geometry section (blending, wall details and speleothems\n"
    "                 per tunnel type, fracture grooves along its fracture families), its seed,\n"
    "                 terrain for --carve, default box\n"
    "  --blend R      smooth-union width at junctions in metres, 0 for a hard union (default:\n"
    "                 geometry.blend, else the smallest radius at each junction)\n"
    "  --no-details   smooth walls (no wall details)\n"
    "  --no-speleothems  no stalactites or stalagmites\n"
    "  --blocks       with --carve: the terrain amplified with the rock blocks of the\n"
    "                 scenario's blocks section (docs/blocks.md), so a cave entrance in a\n"
    "                 cliff of blocks is one mesh\n"
    "  --sdf F.vti    also write the sampled field as VTK image data (contour it at 0)\n"
    "  --noise A      also a solid sparse-Gabor wall noise of at most A metres (default 0)\n"
    "  --radius R     radius of edges without a \"radius\" attribute (default 1 m)\n"
    "  --spheres      fill sharp bends with Poisson spheres (the paper's method, slower and\n"
    "                 bumpier) instead of revolved sections\n"
    "  --seed S       seed of the spheres, noise, details and speleothems (default: the\n"
    "                 scenario's random.seed with --scenario, else 1)\n"
    "  --realisation N  realisation index: details and speleothems are drawn from the stream of\n"
    "                 (seed, N), as karst generate draws realisation N (default 0)\n"
    "  -j THREADS     worker threads, 1 to 1024 (default: all processors)\n"
    "  --quiet        no progress bar and no summary line\n\n"
    "Beside the mesh, STEM.paraview.py (cave.paraview.py for cave.vtp) shows it and the --sdf\n"
    "field in ParaView with karst's colours, category names and units (karst view).\n"
    "The geometry is described in docs/geometry.md.\n"};
