/* Shared libraries opened on first use (PROJ, GDAL, FLANN: src/crs/proj_api.c,
 * src/export/gdal_api.c, src/graph/flann_api.c; karst's own plugins: src/ensemble/mpi_api.c,
 * src/io/vtk_api.c).
 * Each loader lists the symbols it needs (the first three with an X-macro), opens the library
 * once per process (pthread_once) and copies the addresses into its table of typed pointers. */
#ifndef KARST_LIBRARY_INTERNAL_H
#define KARST_LIBRARY_INTERNAL_H

#include <stddef.h>

/** For an X-macro list of symbols: their names, as array initialisers. */
#define KARST_I_SYMBOL_NAME(name) #name,

/**
 * Open the shared library @p file (a soname, or a path; dlopen with RTLD_NOW, and RTLD_GLOBAL
 * when @p global, else RTLD_LOCAL) and look up the @p n symbols @p names into @p syms, all or
 * none: on failure every entry is NULL and @p why holds the reason (dlopen's, or "FILE has no
 * symbol NAME"). The library stays open.
 * @return 0 on success, -1 on failure. Time complexity: O(n) lookups.
 */
int karst_i_library_open(const char *file, int global, const char *const *names, void **syms,
                         size_t n, char *why, size_t why_size);

/**
 * karst_i_library_open for one of karst's own plugins (libkarst_mpi.so, libkarst_vtk.so), built
 * and installed next to libkarst: @p file is looked up in the directory of libkarst's own file
 * (found with dladdr from an address inside it), the build tree and an installed tree alike.
 * @return 0 on success, -1 on failure with the reason in @p why.
 */
int karst_i_library_open_plugin(const char *file, int global, const char *const *names,
                                void **syms, size_t n, char *why, size_t why_size);

/**
 * One of karst's plugins, whose one exported symbol @p entry is a function returning its table
 * of functions, the table starting with an int: its interface version. Opens @p file as
 * karst_i_library_open_plugin does, calls the entry, and checks the version.
 * @return the table, or NULL with the reason in @p why (dlopen's, or "FILE is of another karst"
 *         when the version is not @p version).
 */
const void *karst_i_plugin_table(const char *file, const char *entry, int global, int version,
                                 char *why, size_t why_size);

#endif
