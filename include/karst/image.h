/**
 * @file image.h
 * @brief Greyscale images read from PGM (P2/P5, 8 or 16 bits) and PNG files:
 *        the reliefs of the warping operator (include/karst/implicit.h,
 *        Paris et al. 2020, §4.3 and Fig. 9).
 */
#ifndef KARST_IMAGE_H
#define KARST_IMAGE_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most pixels accepted from a file (2^26: 256 MB of float values). */
#define KARST_IMAGE_MAX_PIXELS ((long long)1 << 26)
/** Largest image file read, in bytes (1 GiB). */
#define KARST_IMAGE_MAX_BYTES ((long long)1 << 30)

/** A greyscale image: @c width x @c height values in [0, 1], row 0 at the top, x fastest. */
typedef struct karst_image {
  int width, height;
  float *v;
} karst_image_t;

/** Empty image (caller-owned storage). */
void karst_image_init(karst_image_t *img);
/** Release the pixels and leave the image empty. */
void karst_image_destroy(karst_image_t *img);

/**
 * Read a greyscale image, the format told by its first bytes: PGM ("P2"
 * ASCII or "P5" binary, maxval 1..65535) or PNG (grey, grey + alpha, RGB,
 * RGBA or palette, 1 to 16 bits). Values are the stored samples divided by
 * the largest one (maxval, or 2^bits - 1), with no gamma conversion (a
 * relief image stores heights); colours become their Rec. 709 luma
 * 0.2126 R + 0.7152 G + 0.0722 B; alpha is ignored.
 * @param img  an initialised image, replaced on success, unchanged on failure
 * @return KARST_SUCCESS; KARST_EIO (missing, unreadable, not a regular file);
 *         KARST_ERANGE (over KARST_IMAGE_MAX_BYTES or KARST_IMAGE_MAX_PIXELS);
 *         KARST_EPARSE ("FILE:LINE: ..." for PGM headers and ASCII pixels,
 *         "FILE: byte N: ..." for binary data, libpng's message for PNG);
 *         KARST_ENOMEM.
 * Time complexity: O(pixels).
 */
karst_error_t karst_image_read(karst_ctx_t *ctx, const char *path, karst_image_t *img);

#ifdef __cplusplus
}
#endif
#endif /* KARST_IMAGE_H */
