/* fuzz_mesh_obj.c — libFuzzer target: OBJ files through the mesh guard
 * (bake/mesh_guard.c); what it checks and how to run it: fuzz_mesh.h. */
#include "fuzz_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    fuzz_mesh_one(MESO_MESH_FORMAT_OBJ, data, size);
    return 0;
}
