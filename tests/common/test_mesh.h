/* test_mesh.h — a test's bundled mesh, read through the OpenMesh adapter
 * (header-only; include after test_util.h). */
#ifndef MESO_TEST_MESH_H
#define MESO_TEST_MESH_H

#include <string.h>

#include "adapters.h"

/* Reads the mesh at `path` into *m; 0 when this build has no OpenMesh (the
 * caller skips its mesh-based checks). A missing or unreadable file fails. */
static inline int test_load_mesh(const char* path, meso_mesh* m)
{
#if MESO_HAVE_OPENMESH
    meso_error err;
    memset(&err, 0, sizeof(err));
    uint32_t dropped = 0;
    if (meso_openmesh_read(path, m, &dropped, &err) != MESO_OK) {
        fprintf(stderr, "    cannot read %s: %s\n", path, err.message);
        assert(!"a bundled mesh is missing or unreadable");
    }
    return 1;
#else
    (void)path;
    (void)m;
    fprintf(stderr, "    built without OpenMesh: skipping mesh-based checks\n");
    return 0;
#endif
}

#endif /* MESO_TEST_MESH_H */
