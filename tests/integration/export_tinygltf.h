/* export_tinygltf.h — tinygltf's GLB parser for test_export_glb.c
 * (export_tinygltf.cpp). */
#ifndef MESO_TEST_EXPORT_TINYGLTF_H
#define MESO_TEST_EXPORT_TINYGLTF_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tg_image {
    int width, height, components; /* 0 when absent */
    unsigned char* pixels;         /* malloc'd, rows top to bottom; free() it */
} tg_image;

/* TinyGLTF::LoadBinaryFromFile(path). Returns 1 when it succeeded; the
 * warnings and errors it reported are copied out (empty when none), with
 * the node count and the decoded images of material 0's normal and
 * base-colour textures. */
int tg_load(const char* path, char* warn, size_t warn_size, char* err, size_t err_size, int* node_count,
            tg_image* normal0, tg_image* color0);

#ifdef __cplusplus
}
#endif
#endif
