/**
 * @file view.h
 * @brief ParaView scripts written beside karst's outputs, and finding them again.
 *
 * Every command that writes files for ParaView (generate, ensemble, mesh) also writes one
 * ParaView Python script beside them, "<stem>.paraview.py" (network.paraview.py,
 * ensemble.paraview.py, cave.paraview.py). The script loads the files (paths relative to
 * itself), colours each categorical array with an annotated categorical lookup table (names
 * read from the file's "*_names" field data, colours from include/karst/palette.h) and each
 * continuous array with the palette's ramp and a colour bar titled with the quantity and unit
 * (include/karst/arrays.h), on a white background, north up. Run it with
 * `paraview --script=network.paraview.py` (karst view does), or headless with
 * `pvbatch network.paraview.py --screenshot view.png --legend legend.json`.
 */
#ifndef KARST_VIEW_H
#define KARST_VIEW_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Suffix of the scripts: "<stem>" KARST_VIEW_SCRIPT_SUFFIX. */
#define KARST_VIEW_SCRIPT_SUFFIX ".paraview.py"

/** How a file is shown. */
typedef enum {
  KARST_VIEW_NETWORK = 0, /**< conduit lines (network.vtp), coloured by tunnel_type */
  KARST_VIEW_SAMPLES = 1, /**< a point cloud (samples.vtp), coloured by source, hidden at start */
  KARST_VIEW_MESH = 2,    /**< a surface (.vtp, .ply, .stl), coloured by tunnel_type, else its first
                             categorical array */
  KARST_VIEW_FIELD = 3,   /**< a scalar field on a grid (.vti): its 0 isosurface and a slice */
  KARST_VIEW_COLLECTION = 4, /**< a ParaView collection (.pvd) of networks, one member a step */
  KARST_VIEW_GEOLOGY = 5,    /**< geological surfaces (geology.vtp), translucent, hidden at start */
  KARST_VIEW_ROLE_COUNT
} karst_view_role_t;

/** One file a script loads. */
typedef struct karst_view_item {
  const char *path; /**< the file (absolute, or relative to the working directory) */
  karst_view_role_t role;
  const char *colour_by; /**< array to colour by at start; NULL: the role's default */
} karst_view_item_t;

/**
 * The script name beside output @p path: its directory, its name without the extension, and
 * KARST_VIEW_SCRIPT_SUFFIX ("out/network.vtp" gives "out/network.paraview.py"). Caller frees;
 * NULL when out of memory.
 */
char *karst_view_script_path(const char *path);

/**
 * Write the ParaView script @p script that shows the @p n files of @p items (their paths are
 * written relative to the directory of @p final_path, the name the script will have, so the
 * directory can be moved). @p script may be a temporary name; the write is atomic.
 */
karst_error_t karst_view_write_script(karst_ctx_t *ctx, const char *script, const char *final_path,
                                      const karst_view_item_t *items, int n);

/**
 * The script to open for @p path: a script itself; a directory holding exactly one
 * "*.paraview.py"; or a data file with a script beside it (karst_view_script_path). @p out
 * receives a path the caller frees. KARST_ENOTFOUND when there is none, KARST_EINVAL when a
 * directory holds several (the message names them).
 */
karst_error_t karst_view_find_script(karst_ctx_t *ctx, const char *path, char **out);

#ifdef __cplusplus
}
#endif
#endif /* KARST_VIEW_H */
