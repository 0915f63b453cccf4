/* mesh_chunk.h — bake meshes to/from MESH chunks (raw or Draco). */
#ifndef MESO_MESH_CHUNK_H
#define MESO_MESH_CHUNK_H

#include "adapters.h"
#include "meso_bake.h"

typedef struct meso_mesh_chunk {
    void* data;            /* malloc'd stored payload: free() it */
    size_t size;           /* stored size */
    uint64_t decoded_size; /* size of the raw layout */
    uint16_t encoding;     /* MESO_ENCODING_RAW or _DRACO */
} meso_mesh_chunk;

/* Build the stored payload of a MESH chunk: raw when draco is NULL,
 * otherwise the 64-byte header plus a Draco bitstream (MESO_ERR_UNSUPPORTED
 * in a build without the Draco adapter). */
meso_result meso_bake_mesh_chunk(const meso_mesh* m, const meso_draco_options* draco, meso_mesh_chunk* out,
                                 meso_error* err);

/* The meso_decoder for MESO_ENCODING_DRACO (decode_fn is NULL without Draco). */
meso_decoder meso_bake_draco_decoder(void);

/* Copy a parsed MESH chunk into a bake mesh. */
meso_result meso_bake_mesh_from_view(const meso_mesh_view* v, meso_mesh* out, meso_error* err);

#endif
