// The public headers compile alone as C++ (extern "C" linkage, no C-only syntax).
#include "meso_file.h"
#include "meso_layout.h"
#include "meso_rt.h"

int main()
{
    meso_rt_desc desc = {};
    meso_rt_draw_desc draw = {}; // value-initialised: every knob at its default
    if (draw.shell.technique != MESO_SHELL_SMOOTH || draw.cells.max_steps != 0 || draw.stats != nullptr)
        return 1;
    meso_rt* rt = nullptr;
    // No GL loader: refused with INVALID_ARG, and the symbol links with C linkage.
    return meso_rt_create(&desc, &rt) == MESO_ERR_INVALID_ARG && rt == nullptr ? 0 : 1;
}
