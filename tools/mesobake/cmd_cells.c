/*
 * cmd_cells.c — `mesobake cells`: a cell-based object
 * (cell-based-object-representation.md ch. 3–4) as one .meso cells object:
 * the base mesh, CELL, TILE, SPLT, MEMB, NRMM and COLR (FORMAT.md §7.2
 * kind 3, §7.8). Stages: tile map (tile_map.h) → split cells
 * (split_cells.h) → exact sparse voxelization and membership
 * (voxelize.h, membership.h) → normal and colour maps (cells_chunks.h)
 * → levels of detail (cells_levels.h, cells_standin.h, mesh_levels.h).
 * The bake is meso_bake_cells (bake/bake_cells.c); this file parses the
 * options.
 */
#include <stdio.h>
#include <string.h>

#include "cli_util.h"

static const char* const usage_cells =
    "Usage: mesobake cells -i MESH -o OUT.meso [options]\n"
    "\n"
    "Fill a mesh with tiled cells: a periodic tile map repeated over a grid of tiles,\n"
    "every cell tagged inside / outside / intersected by an exact voxelization of the\n"
    "mesh at tiles x tile-res voxels per axis, with a normal and a colour map.\n"
    "\n"
    "Input / output:\n"
    "  -i, --input FILE        mesh: .obj .off .ply .stl .om .drc .gltf .glb\n"
    NODE_OPTION_HELP
    "  -o, --output FILE       .meso file to write (atomically; a symbolic link is written\n"
    "                          through, a device, FIFO or directory refused)\n"
    "Grid (a cube of tiles around the mesh, one voxel of padding):\n"
    "      --tiles N           tiles along the longest axis (default 8; N x R <= 16384)\n"
    "      --cell-size S       or: the edge of one tile in mesh units (the tile count follows)\n"
    "      --tile-res R        tile-map voxels per tile edge (default 32, 1..1024)\n"
    "Cells:\n"
    "      --tile-map SPEC     voronoi[:SEEDS[:RNG]]   periodic Voronoi (default voronoi:8:1)\n"
    "                          spheres[:N[:RADIUS]]    N spheres of RADIUS tile edges (default 8, 0.25)\n"
    "                          FILE.raw:R              R^3 little-endian u16 indices, x fastest;\n"
    "                                                  R is the tile resolution (--tile-res must agree)\n"
    "      --colour SPEC       hash[:SEED]  a colour per cell with a little grain (default hash:0)\n"
    "                          FILE.raw:R   R^3 RGBA8 texels, x fastest (R = the tile resolution)\n"
    "                          from-mesh[:G] the input's base colour (glTF: factor x texture) at\n"
    "                                       the mesh point nearest each hit, from a G-sample grid\n"
    "                                       along the longest side (default 64, 2..256; stored\n"
    "                                       as TX3D); it replaces the cells' colours. No base\n"
    "                                       colour in the input: exit 3 (E3562)\n"
    "      --color SPEC        the same as --colour\n"
    "      --voxelizer V       auto (default): parity for closed meshes, else winding\n"
    "                          parity, vdb: exact ray parity (closed meshes only; 'vdb' is an alias:\n"
    "                          the exact path replaced OpenVDB, which misclassifies near the surface)\n"
    "                          winding: generalized winding number (open or defective meshes)\n";
/* The rest (one string would pass the 4095 characters C99 promises). */
static const char* const usage_cells_levels =
    "Levels of detail:\n"
    "      --levels auto|N     auto (default): native coarser levels first, the tile map halved\n"
    "                          each level (down to 4 voxels a tile edge; each cell keeps its tag,\n"
    "                          colours averaged), each with its error measured against level 0's\n"
    "                          voxel faces, kept while below the base mesh's; then the base mesh,\n"
    "                          drawn as a plain mesh in the object's place, with its error: a\n"
    "                          measured bound of the distance between it and the cells' voxel\n"
    "                          faces drawn, both ways (empty cells carve below the mesh); then the\n"
    "                          base mesh's simplified levels (meshoptimizer, as mesobake mesh\n"
    "                          --levels auto), each with the base's error plus its own (LODS).\n"
    "                          Every mesh level carries the cells' colours around each vertex\n"
    "                          (VCOL). N (1..9): at most N levels; 1 = level 0 only (no LODS chunk),\n"
    "                          2 = the base mesh only, then native levels, then simplified ones\n"
    "Other:\n"
    "  -j, --threads N         threads (default: all cores); the output does not depend on it\n"
    "      --report FILE       the bake report as JSON: tiles, split_cells, cells_inside,\n"
    "                          cells_outside, cells_intersected, bytes, seconds_total, voxelizer,\n"
    "                          levels (lod, form, error, triangles, mesh_bytes, colour_bytes), ...\n"
    MEMORY_OPTION_HELP
    "  -v, --verbose           one line per stage on stderr\n"
    "  -h, --help              this text\n";

typedef struct cells_args {
    const char *out, *report;
    meso_bake_cells_options o;
} cells_args;

static int parse_args(int argc, char** argv, cells_args* a)
{
    *a = (cells_args){.o = meso_bake_cells_defaults()};
    meso_bake_cells_options* o = &a->o;
    cli_bake_common(&o->common);
    o->tile_map = "voronoi";
    o->colour = "hash";
    o->voxelizer = "auto";
    long n;
    for (int i = 0; i < argc; ++i) {
        const char* s = argv[i];
        const char* v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(s, "-h") || !strcmp(s, "--help")) {
            fputs(usage_cells, stdout);
            print_help(usage_cells_levels);
            return -1;
        } else if (!strcmp(s, "-v") || !strcmp(s, "--verbose")) {
            verbose = 1;
            continue;
        }
        static const char* const valued[] = {"-i", "--input", "-o", "--output", "--report", "--max-memory", "--tiles", "--cell-size",
            "--tile-res", "--tile-map", "--colour", "--color", "--voxelizer", "-j", "--threads", "--levels"};
        int handled, code;
        if (!bake_option(s, v, valued, sizeof valued / sizeof valued[0], &o->input, &a->out, &a->report,
                         &o->common.max_memory, &handled, &code))
            return code;
        ++i;
        if (handled)
            continue;
        if (!strcmp(s, "--tile-map"))
            o->tile_map = v;
        else if (!strcmp(s, "--colour") || !strcmp(s, "--color"))
            o->colour = v;
        else if (!strcmp(s, "--voxelizer")) {
            if (strcmp(v, "auto") && strcmp(v, "vdb") && strcmp(v, "parity") && strcmp(v, "winding"))
                return usage_error("--voxelizer expects auto, vdb, parity or winding, got '%s'", v);
            o->voxelizer = v;
        } else if (!strcmp(s, "--levels")) {
            if (!strcmp(v, "auto"))
                o->levels = 0;
            else if (meso_bake_parse_long(v, 1, MESO_BAKE_CELLS_MAX_LEVELS, &n))
                o->levels = (int)n;
            else
                return usage_error("--levels expects auto or a level count in 1..%u, got '%s'",
                                   MESO_BAKE_CELLS_MAX_LEVELS, v);
        } else if (!strcmp(s, "--tiles")) {
            if (!meso_bake_parse_long(v, 1, MESO_BAKE_MAX_TILES, &n))
                return usage_error("--tiles expects an integer in 1..16384, got '%s'", v);
            o->tiles = (uint32_t)n;
        } else if (!strcmp(s, "--tile-res")) {
            if (!meso_bake_parse_long(v, 1, MESO_BAKE_MAX_TILE_RES, &n))
                return usage_error("--tile-res expects an integer in 1..%u, got '%s'", MESO_BAKE_MAX_TILE_RES, v);
            o->tile_res = (uint32_t)n;
        } else if (!strcmp(s, "-j") || !strcmp(s, "--threads")) {
            if (!meso_bake_parse_long(v, 1, 1024, &n))
                return usage_error("%s expects a thread count in 1..1024, got '%s'", s, v);
            o->common.threads = (int)n;
        } else if (!strcmp(s, "--cell-size")) {
            if (!meso_bake_parse_positive(v, &o->cell_size))
                return usage_error("--cell-size expects a positive length, got '%s'", v);
        }
    }
    if (!o->input || !a->out)
        return usage_error("cells needs -i MESH and -o OUT.meso");
    if (o->tiles && o->cell_size > 0)
        return usage_error("option --tiles can not be used together with --cell-size");
    return check_outputs(a->out, a->report);
}

int cmd_cells(int argc, char** argv)
{
    cells_args a;
    const int pr = parse_args(argc, argv, &a);
    if (pr != 0)
        return pr < 0 ? MESO_EXIT_OK : pr;
    const double t0 = meso_seconds();
    meso_error err = {0};
    meso_bake_output* baked = NULL;
    const meso_result r = meso_bake_cells(&a.o, &baked, NULL, &err);
    return finish_bake(r, &err, baked, a.out, a.report, t0, NULL);
}
