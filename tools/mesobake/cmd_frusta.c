/*
 * cmd_frusta.c — `mesobake frusta`: a skeleton (SWC, the text format of
 * skeleton_swc.h, or one extracted from a closed mesh) skinned with conical
 * frusta (relief-mapped-conical-frusta.md §2, bake/frustum_model.h), with an
 * optional relief map (§3) and colour map, as one .meso frusta object:
 * SKEL, FRUS, FSEG, BALL, RELF and COLR (FORMAT.md §7.2 kind 4), and by
 * default a triangle tessellation as level 1 (MESH at lod 1, LODS; FORMAT.md
 * §7.10). The bake is meso_bake_frusta
 * (bake/bake_frusta.c); this file parses the options.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"

static const char* const usage_frusta =
    "Usage: mesobake frusta -i INPUT -o OUT.meso [options]\n"
    "\n"
    "Skin a skeleton with conical frusta: one cone per segment, one cutting plane\n"
    "per joint (fitted so neighbouring cuts are one ellipse), balls at branch points\n"
    "and at joints too sharp for a plane. Optionally relief mapped.\n"
    "\n"
    "Input / output:\n"
    "  -i, --input FILE        .swc      SWC skeleton: id type x y z radius parent\n"
    "                          .skel     text skeleton: x y z radius [parent] [twist=DEG] per\n"
    "                                    line (parent: 1-based node number, 0 = root; omitted:\n"
    "                                    the previous node; twist=DEG: the segment from the\n"
    "                                    parent to this node twists DEG degrees, replacing\n"
    "                                    --twist there)\n"
    "                          a mesh    .obj .off .ply .stl .om .drc .gltf .glb: closed, one\n"
    "                                    component (glTF: --node NAME|INDEX picks one node);\n"
    "                                    skeleton by mean-curvature flow (CGAL), radii\n"
    "                                    fitted to the mesh, simplified to --tolerance\n"
    "  -o, --output FILE       .meso file to write (atomically; a symbolic link is written\n"
    "                          through, a device, FIFO or directory refused)\n"
    "Shape:\n"
    "      --tolerance T       mesh input: largest distance of the frusta from the mesh\n"
    "                          after simplification (default: 1% of the bounding-box diagonal)\n"
    "      --max-joint-angle D joints bending more than D degrees become ball joints\n"
    "                          (default 150; 0 = no limit)\n"
    "      --no-fit            keep the node radii at joints (skip the paper's minor-axis fit;\n"
    "                          the cuts then leave a seam gap, the report says how large)\n"
    "      --keep-cap-intersections\n"
    "                          keep the paper's planes where caps intersect at sharp joints\n"
    "                          (default: ball joints there); for reproducing the failure\n"
    "Relief (a height field between the cone, w = 0, and the cone + depth, w = 1), colour:\n"
    "      --relief SPEC       height:FILE.png, bricks[:RES], cobble[:RES] or ribs[:RES]\n"
    "      --relief-depth D    depth in skeleton units (default: a quarter of the mean radius)\n"
    "      --relief-repeat N   tiles around the circumference (default 1; along the axis the\n"
    "                          texture keeps texels square and runs on across joints)\n"
    "      --relief-color FILE.png\n"
    "                          colour map (8-bit PNG, sRGB) running with the relief: sampled\n"
    "                          at the relief map's (s, t), so it repeats (--relief-repeat),\n"
    "                          twists and runs on across joints as the relief does (stored\n"
    "                          as COLR); without --relief it colours the plain frusta with\n"
    "                          the same coordinates. Balls take the map's mean colour.\n"
    "                          Missing file: exit 2 (E3560); not an 8-bit PNG: exit 3 (E3561)\n"
    "      --twist DEG         twist the texture DEG degrees per unit of skeleton length\n"
    "                          (default 0): a segment of length L twists DEG x L degrees, so\n"
    "                          the pattern turns uniformly whatever the segmentation (the\n"
    "                          joints' u alignment accounts for it); DEG > 0 makes lines of\n"
    "                          constant u left-handed helices; |DEG| <= 360000, and at most\n"
    "                          1000 turns per segment\n";

static const char* const usage_frusta_end =
    "Levels of detail:\n"
    "      --levels auto|N     auto (default): with a relief, native levels first: the same frusta\n"
    "                          with the relief map halved (a RELF of its own at lod l; error: the\n"
    "                          exact sup of the height change times the largest relief depth x\n"
    "                          slide gain below; up to 4, kept while each draws from at most 9/10\n"
    "                          of the bytes of the level before); then coarser skeletons (up to\n"
    "                          3, untwisted frusta only): chains of joints merged into fewer\n"
    "                          frusta (their own FRUS, FSEG, BALL at their lod, level 0's SKEL),\n"
    "                          drawing the coarsest relief; error: that relief's plus the measured\n"
    "                          distance between points with the same relief coordinates (or, with\n"
    "                          no relief or colour, any such pairing); each drops at least a\n"
    "                          quarter of the frusta; report: skeleton_levels); then the frusta\n"
    "                          as a plain triangle mesh (a MESH) drawn where its error is under the pixel\n"
    "                          budget: every frustum, cap and ball tessellated at the mid-relief\n"
    "                          cone (relief not in the vertices), a few cells around each part;\n"
    "                          its error (object units, both ways, stored in LODS and reported in\n"
    "                          levels[]) is half the relief's height range, scaled by how far a\n"
    "                          tilted cutting plane lets the surface slide, plus the chord error;\n"
    "                          then its simplifications (meshoptimizer, as mesobake mesh), each\n"
    "                          with the tessellation's error plus its own; with --relief-color\n"
    "                          each carries the map's colour and the relief's darkening around\n"
    "                          each vertex (VCOL). N (1..16): at most N\n"
    "                          levels (at most 9 are made; 2 = the tessellation only, N >= 3 the\n"
    "                          tessellation, then native levels, then simplified ones); 1: level 0\n"
    "                          only, no LODS chunk (the file of earlier bakes)\n"
    "Other:\n"
    "      --report FILE       the bake report as JSON: segments, joints, branch_points,\n"
    "                          cap_intersections_found, cap_intersections_unhandled,\n"
    "                          fit_error_max, fit_error_mean, seconds_total, bytes, ...\n"
    MEMORY_OPTION_HELP
    "  -v, --verbose           one line per stage on stderr\n"
    "  -h, --help              this text\n"
    "\n"
    "fit_error: mesh input: two-sided distance between the frusta (as round-ended cones)\n"
    "and the mesh (max), mean distance of the mesh's vertices to them;\n"
    "skeleton input: how far the fit moved the surface from the input radii.\n"
    "\n"
    "Skeletons with nothing to draw are invalid input (exit 3): a single node, every\n"
    "radius 0, only zero-length segments; so are coordinates or radii beyond 1e15.\n";

/* A finite number of degrees within +-MESO_BAKE_MAX_TWIST (strtod syntax,
 * the whole string). */
static int parse_twist(const char* s, double* out)
{
    char* end = NULL;
    if (!s || !*s)
        return 0;
    const double x = strtod(s, &end);
    if (*end != '\0' || !isfinite(x) || fabs(x) > MESO_BAKE_MAX_TWIST)
        return 0;
    *out = x;
    return 1;
}

typedef struct frusta_args {
    const char *out, *report;
    meso_bake_frusta_options o;
} frusta_args;

static int parse_args(int argc, char** argv, frusta_args* a)
{
    *a = (frusta_args){.o = meso_bake_frusta_defaults()};
    meso_bake_frusta_options* o = &a->o;
    cli_bake_common(&o->common);
    for (int i = 0; i < argc; ++i) {
        const char* s = argv[i];
        const char* v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(s, "-h") || !strcmp(s, "--help")) {
            fputs(usage_frusta, stdout);
            print_help(usage_frusta_end);
            return -1;
        } else if (!strcmp(s, "-v") || !strcmp(s, "--verbose")) {
            verbose = 1;
            continue;
        } else if (!strcmp(s, "--no-fit")) {
            o->no_fit = 1;
            continue;
        } else if (!strcmp(s, "--keep-cap-intersections")) {
            o->keep_cap_intersections = 1;
            continue;
        }
        static const char* const valued[] = {"-i", "--input", "-o", "--output", "--report", "--max-memory", "--tolerance",
            "--max-joint-angle", "--relief", "--relief-depth", "--relief-repeat", "--relief-color", "--twist", "--levels"};
        int handled, code;
        if (!bake_option(s, v, valued, sizeof valued / sizeof valued[0], &o->input, &a->out, &a->report,
                         &o->common.max_memory, &handled, &code))
            return code;
        ++i;
        if (handled)
            continue;
        if (!strcmp(s, "--relief"))
            o->relief = v;
        else if (!strcmp(s, "--relief-color"))
            o->relief_color = v;
        else if (!strcmp(s, "--levels")) {
            long n;
            if (!strcmp(v, "auto"))
                o->levels = 0;
            else if (meso_bake_parse_long(v, 1, MESO_BAKE_FRUSTA_MAX_LEVELS, &n))
                o->levels = (int)n;
            else
                return usage_error("--levels expects auto or a level count in 1..%u, got '%s'",
                                   MESO_BAKE_FRUSTA_MAX_LEVELS, v);
        } else if (!strcmp(s, "--tolerance")) {
            if (!meso_bake_parse_positive(v, &o->tolerance))
                return usage_error("--tolerance expects a positive length, got '%s'", v);
        } else if (!strcmp(s, "--max-joint-angle")) {
            if (!strcmp(v, "0"))
                o->max_joint_angle = 0;
            else if (!meso_bake_parse_positive(v, &o->max_joint_angle) || o->max_joint_angle > 180)
                return usage_error("--max-joint-angle expects degrees in [0, 180], got '%s'", v);
        } else if (!strcmp(s, "--relief-depth")) {
            if (!meso_bake_parse_positive(v, &o->relief_depth))
                return usage_error("--relief-depth expects a positive length, got '%s'", v);
        } else if (!strcmp(s, "--twist")) {
            if (!parse_twist(v, &o->twist))
                return usage_error("--twist expects a finite angle in degrees per unit length within +-%g, got '%s'",
                                   MESO_BAKE_MAX_TWIST, v);
        } else if (!strcmp(s, "--relief-repeat")) {
            if (!meso_bake_parse_positive(v, &o->relief_repeat) || o->relief_repeat > 1e4)
                return usage_error("--relief-repeat expects a number in (0, 10000], got '%s'", v);
        }
    }
    if (!o->input || !a->out)
        return usage_error("frusta needs -i INPUT and -o OUT.meso");
    if (o->relief_depth > 0 && !o->relief)
        return usage_error("--relief-depth needs --relief");
    return check_outputs(a->out, a->report);
}

int cmd_frusta(int argc, char** argv)
{
    frusta_args a;
    const int pr = parse_args(argc, argv, &a);
    if (pr != 0)
        return pr < 0 ? MESO_EXIT_OK : pr;
    const double t0 = meso_seconds();
    meso_error err = {0};
    meso_bake_output* baked = NULL;
    const meso_result r = meso_bake_frusta(&a.o, &baked, NULL, &err);
    return finish_bake(r, &err, baked, a.out, a.report, t0, NULL);
}
