// meso_bake.h compiles alone as C++ (extern "C" linkage, no C-only syntax).
#include "meso_bake.h"

int main()
{
    meso_bake_mesh_options o = meso_bake_mesh_defaults();
    meso_bake_output* out = nullptr;
    meso_error err = {};
    // No input: refused, and the symbols link with C linkage.
    return meso_bake_mesh(&o, &out, nullptr, &err) != MESO_OK && out == nullptr ? 0 : 1;
}
