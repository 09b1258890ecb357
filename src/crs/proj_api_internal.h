/* PROJ's C API as karst uses it (src/crs/crs_frame.c), loaded on first use.
 *
 * libproj brings about 35 shared libraries that nothing else in libkarst needs (libcurl and its
 * TLS and LDAP stack, libtiff, SQLite, ...); linked into libkarst, loading and relocating them
 * cost every karst process about 15-20 ms at start-up (measured on the 2-core project machine:
 * an empty program linked with -lproj starts in 20 ms, without it in 1 ms), though only
 * scenarios and surveys with an EPSG code or a PROJ string need PROJ (UTM zones and WGS 84
 * go through GeographicLib). So libkarst is not linked with it: the first such coordinate
 * system opens the library with dlopen (its soname, KARST_PROJ_SONAME, fixed when karst is
 * configured) and looks up the functions below, typed from PROJ's own header. */
#ifndef KARST_PROJ_API_INTERNAL_H
#define KARST_PROJ_API_INTERNAL_H

#include <proj.h>

#include "karst/common.h"

#define KARST_I_PROJ_FUNCTIONS(X)                                                                  \
  X(proj_as_proj_string)                                                                           \
  X(proj_as_wkt)                                                                                   \
  X(proj_clone)                                                                                    \
  X(proj_context_create)                                                                           \
  X(proj_context_destroy)                                                                          \
  X(proj_context_errno)                                                                            \
  X(proj_context_errno_string)                                                                     \
  X(proj_context_set_enable_network)                                                               \
  X(proj_coord)                                                                                    \
  X(proj_coordoperation_get_accuracy)                                                              \
  X(proj_create)                                                                                   \
  X(proj_create_crs_to_crs_from_pj)                                                                \
  X(proj_crs_get_sub_crs)                                                                          \
  X(proj_destroy)                                                                                  \
  X(proj_get_id_auth_name)                                                                         \
  X(proj_get_id_code)                                                                              \
  X(proj_get_name)                                                                                 \
  X(proj_get_type)                                                                                 \
  X(proj_info)                                                                                     \
  X(proj_is_crs)                                                                                   \
  X(proj_log_level)                                                                                \
  X(proj_normalize_for_visualization)                                                              \
  X(proj_trans)                                                                                    \
  X(proj_trans_get_last_used_operation)

/** The loaded functions: karst_i_proj.proj_create(...) and so on. */
typedef struct {
#define KARST_I_PROJ_POINTER(name) __typeof__(name) *name;
  KARST_I_PROJ_FUNCTIONS(KARST_I_PROJ_POINTER)
#undef KARST_I_PROJ_POINTER
} karst_i_proj_t;

extern karst_i_proj_t karst_i_proj;

/**
 * Load PROJ once per process (thread-safe); later calls return the first call's result.
 * @return KARST_SUCCESS, or KARST_ENOTIMPL with a message naming the library and dlopen's or
 *         dlsym's reason when PROJ cannot be loaded.
 */
karst_error_t karst_i_proj_load(karst_ctx_t *ctx);

#endif
