/*
 * ref_common.h — what the CPU references share (internal, not installed):
 * reading an object's chunks, and the camera, pixel rays, window depth,
 * shading and image buffers of shell_reference.h's conventions, so the
 * shell and the frusta references render with exactly the same rays and
 * light.
 */
#ifndef MESO_REF_COMMON_H
#define MESO_REF_COMMON_H

#include <stddef.h>
#include <stdint.h>

#include "meso_file.h"
#include "shell_reference.h"

/* >>files */

/* Fills err (message "<what> <id>: <msg>") and returns r. */
meso_result mesoi_ref_fail(meso_error* err, meso_result r, const char* what, uint32_t id, const char* msg);

/* The OBJT record of object `id`, which must be of `kind` (MESO_OBJECT_*);
 * `what` names the kind in messages. MESO_ERR_NOT_FOUND: no such object;
 * MESO_ERR_INVALID_ARG: another kind. */
meso_result mesoi_ref_object(meso_file* f, uint32_t id, uint32_t kind, const char* what, meso_object_record* out,
    meso_error* err);


/* Chunk `ci` read whole (meso_file_read_chunk) into a new malloc'd buffer. */
meso_result mesoi_ref_read_whole(meso_file* f, int32_t ci, void** out, size_t* size, meso_error* err);

/* A U8 or U16 × 1 texture chunk as floats value / max (malloc'd, x
 * fastest). MESO_ERR_UNSUPPORTED for any other dtype or component count,
 * or a size that does not match dims. */
meso_result mesoi_ref_read_unorm(meso_file* f, int32_t ci, float** values, meso_error* err);

/* >>camera */

typedef struct mesoi_ref_camera {
    double mvp[16], inv[16]; /* proj · view · model and its inverse */
    double light[3];         /* object space, unit */
    double albedo[3];
} mesoi_ref_camera;

/* From a view (zero model = identity, zero light and albedo = defaults).
 * Returns 0 when the matrices are singular. */
int mesoi_ref_camera_init(const meso_ref_view* v, mesoi_ref_camera* c);

/* Object-space ray of pixel (x, y) of a W × H image: o on the near plane, d
 * to the far plane (t ∈ [0, 1] spans the view frustum). */
void mesoi_ref_pixel_ray(const mesoi_ref_camera* c, int x, int y, int W, int H, double o[3], double d[3]);

/* Window depth of an object-space point: 0.5 · z_clip / w_clip + 0.5. */
float mesoi_ref_depth(const mesoi_ref_camera* c, const double p[3]);

/* albedo · (0.25 + 0.75 w) · (0.15 + 0.85 max(0, n·l)), n normalised and
 * turned to face the ray d; writes the colour and that normal. */
void mesoi_ref_shade(const mesoi_ref_camera* c, const double d[3], const double n_in[3], double w, float rgb[3],
    float nrm[3]);
/* The same with the albedo given (a shell's colour at the hit). */
void mesoi_ref_shade_albedo(const mesoi_ref_camera* c, const double albedo[3], const double d[3], const double n_in[3],
                            double w, float rgb[3], float nrm[3]);

/* >>images */

/* Allocates out's buffers for W × H (MESO_ERR_OUT_OF_MEMORY, out zeroed). */
meso_result mesoi_ref_image_alloc(meso_ref_image* out, int W, int H);

/* Calls row(user, y) for every y in 0..height - 1 on `threads` threads (0:
 * all cores, at most 64), thread k taking rows k, k + threads, ...; rows
 * must be independent, so the result never depends on the thread count. A
 * thread that cannot be started has its rows done by the caller. */
void mesoi_ref_rows(int height, int threads, void (*row)(const void* user, int y), const void* user);

/* Pixel px as background (coverage 0, depth 1, hit NaN, normal 0). */
void mesoi_ref_image_miss(meso_ref_image* img, size_t px);

#endif /* MESO_REF_COMMON_H */
