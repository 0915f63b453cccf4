/*
 * cmd_frusta.c — `mesobake frusta`: a skeleton (SWC, the text format of
 * skeleton_swc.h, or one extracted from a closed mesh) skinned with conical
 * frusta (relief-mapped-conical-frusta.md §2, bake/frustum_model.h), with an
 * optional relief map (§3), as one .meso frusta object: SKEL, FRUS, FSEG,
 * BALL and RELF (FORMAT.md §7.2 kind 4).
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"
#include "frusta_chunks.h"
#include "frustum_model.h"
#include "memory_budget.h"
#include "skeleton_swc.h"
#include "texture_function.h"
#if MESO_HAVE_CGAL
#include "skeleton_from_mesh.h"
#endif

static const char* const usage_frusta =
    "Usage: mesobake frusta -i INPUT -o OUT.meso [options]\n"
    "\n"
    "Skin a skeleton with conical frusta: one cone per segment, one cutting plane\n"
    "per joint (fitted so neighbouring cuts are one ellipse), balls at branch points\n"
    "and at joints too sharp for a plane. Optionally relief mapped.\n"
    "\n"
    "Input / output:\n"
    "  -i, --input FILE        .swc      SWC skeleton: id type x y z radius parent\n"
    "                          .skel     text skeleton: x y z radius [parent] per line\n"
    "                                    (parent: 1-based node number, 0 = root; omitted:\n"
    "                                    the previous node)\n"
    "                          a mesh    .obj .off .ply .stl .om: closed, one component;\n"
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
    "Relief (a height field between the cone, w = 0, and the cone + depth, w = 1):\n"
    "      --relief SPEC       height:FILE.png, bricks[:RES], cobble[:RES] or ribs[:RES]\n"
    "      --relief-depth D    depth in skeleton units (default: a quarter of the mean radius)\n"
    "      --relief-repeat N   tiles around the circumference (default 1; along the axis the\n"
    "                          texture keeps texels square and runs on across joints)\n"
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

typedef struct frusta_args {
    const char *in, *out, *report, *relief;
    double tolerance, max_joint_angle, relief_depth, relief_repeat;
    int no_fit, keep_caps;
    uint64_t max_memory; /* --max-memory; 0 until parsed = the default */
} frusta_args;

static int parse_args(int argc, char** argv, frusta_args* a)
{
    *a = (frusta_args){.max_joint_angle = 150, .relief_repeat = 1};
    for (int i = 0; i < argc; ++i) {
        const char* s = argv[i];
        const char* v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(s, "-h") || !strcmp(s, "--help")) {
            print_help(usage_frusta);
            return -1;
        } else if (!strcmp(s, "-v") || !strcmp(s, "--verbose")) {
            verbose = 1;
            continue;
        } else if (!strcmp(s, "--no-fit")) {
            a->no_fit = 1;
            continue;
        } else if (!strcmp(s, "--keep-cap-intersections")) {
            a->keep_caps = 1;
            continue;
        }
        static const char* const valued[] = {"-i", "--input", "-o", "--output", "--report", "--max-memory", "--tolerance",
            "--max-joint-angle", "--relief", "--relief-depth", "--relief-repeat"};
        const int bad = option_value(s, v, valued, sizeof valued / sizeof valued[0]);
        if (bad)
            return bad;
        ++i;
        if (path_option(s, v, &a->in, &a->out, &a->report))
            continue;
        int bad_size = 0;
        if (memory_option(s, v, &a->max_memory, &bad_size)) {
            if (bad_size)
                return bad_size;
            continue;
        }
        if (!strcmp(s, "--relief"))
            a->relief = v;
        else if (!strcmp(s, "--tolerance")) {
            if (!parse_double(v, &a->tolerance))
                return usage_error("--tolerance expects a positive length, got '%s'", v);
        } else if (!strcmp(s, "--max-joint-angle")) {
            if (!strcmp(v, "0"))
                a->max_joint_angle = 0;
            else if (!parse_double(v, &a->max_joint_angle) || a->max_joint_angle > 180)
                return usage_error("--max-joint-angle expects degrees in [0, 180], got '%s'", v);
        } else if (!strcmp(s, "--relief-depth")) {
            if (!parse_double(v, &a->relief_depth))
                return usage_error("--relief-depth expects a positive length, got '%s'", v);
        } else if (!strcmp(s, "--relief-repeat")) {
            if (!parse_double(v, &a->relief_repeat) || a->relief_repeat > 1e4)
                return usage_error("--relief-repeat expects a number in (0, 10000], got '%s'", v);
        }
    }
    if (!a->in || !a->out)
        return usage_error("frusta needs -i INPUT and -o OUT.meso");
    if (a->relief_depth > 0 && !a->relief)
        return usage_error("--relief-depth needs --relief");
    return check_outputs(a->out, a->report);
}

static int is_mesh_path(const char* p)
{
    static const char* const ext[] = {".obj", ".off", ".ply", ".stl", ".om", ".drc"};
    for (size_t i = 0; i < sizeof(ext) / sizeof(ext[0]); ++i)
        if (has_suffix(p, ext[i]))
            return 1;
    return 0;
}

typedef struct skeleton_source {
    const char* kind; /* "swc", "text", "mesh" */
    double fit_error_max, fit_error_mean; /* mesh input: distances to the mesh */
    double mesh_to_model_max, model_to_mesh_max, bbox_diagonal;
    double tolerance;
    uint32_t mesh_triangles, skeleton_nodes_before;
    double seconds_skeleton;
} skeleton_source;

/* Limits up front: a skeleton file's nodes (at most its lines) against the
 * budget before it is read and parsed (memory_budget.h). */
static meso_result check_skeleton_size(const frusta_args* a, meso_error* err)
{
    uint64_t bytes = 0, lines = 0;
    meso_error ignored = {0};
    if (meso_count_lines(a->in, &bytes, &lines, &ignored) != MESO_OK)
        return MESO_OK; /* the reader reports an unreadable file in its own words */
    return meso_budget_check(meso_skeleton_estimate(bytes, lines), a->max_memory, MESO_LIMIT_ISSUE_SKELETON, err,
                              "skeleton %s (%llu bytes, up to %llu nodes)", a->in, (unsigned long long)bytes,
                              (unsigned long long)lines);
}

static meso_result load_skeleton(const frusta_args* a, meso_skeleton* sk, skeleton_source* src, meso_error* err)
{
    if (!is_mesh_path(a->in)) {
        const meso_result r = check_skeleton_size(a, err);
        if (r != MESO_OK)
            return r;
    }
    if (has_suffix(a->in, ".swc")) {
        src->kind = "swc";
        return meso_skeleton_load(a->in, MESO_SKELETON_SWC, sk, err);
    }
    if (!is_mesh_path(a->in)) {
        src->kind = "text";
        return meso_skeleton_load(a->in, MESO_SKELETON_TEXT, sk, err);
    }
    src->kind = "mesh";
#if MESO_HAVE_CGAL
    meso_mesh m;
    meso_result r = load_mesh(a->in, a->max_memory, &m, err);
    if (r != MESO_OK)
        return r;
    double t0 = meso_seconds();
    meso_skeleton_fit_options o = {.tolerance = a->tolerance};
    meso_skeleton_fit_stats st;
    r = meso_skeleton_from_mesh(&m, &o, sk, &st, err);
    if (r == MESO_OK) {
        /* Two-sided: the mesh's vertices to the frusta and sampled frusta
         * surface back to the mesh. */
        src->fit_error_max = st.hausdorff;
        src->fit_error_mean = st.fit_error_mean;
        src->mesh_to_model_max = st.fit_error_max;
        src->model_to_mesh_max = st.model_to_mesh_max;
        src->bbox_diagonal = st.bbox_diagonal;
        src->tolerance = st.tolerance;
        src->skeleton_nodes_before = st.cgal_nodes;
        src->mesh_triangles = st.mesh_triangles;
        src->seconds_skeleton = meso_seconds() - t0;
        if (verbose)
            fprintf(stderr,
                "mesobake: skeleton: CGAL %u nodes (%.2f s), %u cycles cut, fitted %u nodes / %u segments; fit "
                "error max %.4g (%.2f %% of the diagonal), mean %.4g\n",
                st.cgal_nodes, st.seconds_cgal, st.cycles_broken, st.nodes, st.segments, st.hausdorff,
                100 * st.hausdorff / st.bbox_diagonal, st.fit_error_mean);
    }
    meso_mesh_free(&m);
    return r;
#else
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0,
        "%s: skeletons from meshes need CGAL, which this build does not have", a->in);
#endif
}

static cJSON* report_json(const meso_frustum_model* m, const skeleton_source* src, double fit_max, double fit_mean,
    const meso_frusta_object* o)
{
    const meso_frustum_stats* st = &m->stats;
    cJSON* rep = cJSON_CreateObject();
    cJSON_AddNumberToObject(rep, "segments", st->segments);
    cJSON_AddNumberToObject(rep, "joints", st->joints);
    cJSON_AddNumberToObject(rep, "branch_points", st->branch_points);
    cJSON_AddNumberToObject(rep, "cap_intersections_found", st->cap_intersections_found);
    cJSON_AddNumberToObject(rep, "cap_intersections_unhandled", st->cap_intersections_unhandled);
    cJSON_AddNumberToObject(rep, "fit_error_max", fit_max);
    cJSON_AddNumberToObject(rep, "fit_error_mean", fit_mean);
    cJSON_AddStringToObject(rep, "input", src->kind);
    cJSON_AddNumberToObject(rep, "tips", st->tips);
    cJSON_AddNumberToObject(rep, "balls", o->ball_count);
    cJSON_AddNumberToObject(rep, "ball_joints", st->ball_joints);
    cJSON_AddNumberToObject(rep, "sharp_joints", st->sharp_joints);
    cJSON_AddNumberToObject(rep, "unfitted_joints", st->unfitted_joints);
    cJSON_AddNumberToObject(rep, "degenerate_segments", st->degenerate_segments);
    cJSON_AddNumberToObject(rep, "seam_gap_max", st->seam_gap_max);
    cJSON_AddNumberToObject(rep, "seam_gap_mean", st->seam_gap_mean);
    cJSON_AddNumberToObject(rep, "radius_change_max", st->radius_change_max);
    if (!strcmp(src->kind, "mesh")) {
        cJSON_AddNumberToObject(rep, "tolerance", src->tolerance);
        cJSON_AddNumberToObject(rep, "bbox_diagonal", src->bbox_diagonal);
        cJSON_AddNumberToObject(rep, "mesh_to_frusta_max", src->mesh_to_model_max);
        cJSON_AddNumberToObject(rep, "frusta_to_mesh_max", src->model_to_mesh_max);
        cJSON_AddNumberToObject(rep, "mesh_triangles", src->mesh_triangles);
        cJSON_AddNumberToObject(rep, "skeleton_nodes_extracted", src->skeleton_nodes_before);
    }
    return rep;
}

int cmd_frusta(int argc, char** argv)
{
    frusta_args a;
    int pr = parse_args(argc, argv, &a);
    if (pr != 0)
        return pr < 0 ? MESO_EXIT_OK : pr;
    if (!a.max_memory)
        a.max_memory = meso_memory_default_budget();
    const double t0 = meso_seconds();
    meso_error err = {0};
    meso_skeleton sk = {0};
    meso_frustum_model m = {0};
    meso_frusta_object obj = {0};
    meso_texfn relief = {0};
    skeleton_source src = {0};
    uint8_t *frus = NULL, *fseg = NULL, *ball = NULL;
    cJSON *meta = NULL, *rep = NULL;
    size_t file_size = 0;

    meso_result r = load_skeleton(&a, &sk, &src, &err);
    if (r == MESO_OK && strcmp(src.kind, "mesh") != 0) /* nothing to draw is an invalid input, not a bake */
        r = meso_skeleton_require_drawable(&sk, &err);
    if (r == MESO_OK && verbose)
        fprintf(stderr, "mesobake: %s: %u nodes, %u roots (%s input)\n", a.in, sk.node_count, sk.root_count, src.kind);
    if (r == MESO_OK && a.relief) {
        r = meso_texfn_from_spec_max(a.relief, a.max_memory, &relief, &err);
        if (r == MESO_OK && relief.kind != MESO_TEXFN_HEIGHT)
            r = meso_bake_fail(&err, MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC,
                "--relief '%s' is a volume; frusta take height fields (height:FILE.png, bricks, cobble, ribs)", a.relief);
    }
    if (r == MESO_OK) {
        meso_frustum_options fo = {.keep_cap_intersections = a.keep_caps, .no_minor_axis_fit = a.no_fit,
                                   .max_joint_angle_deg = a.max_joint_angle};
        r = meso_frustum_model_build(&sk, &fo, &m, &err);
    }
    if (r == MESO_OK && verbose)
        fprintf(stderr,
            "mesobake: %u frusta, %u joints (%u ball joints: %u sharp, %u unfitted, cap intersections %u found, %u "
            "unhandled), %u branch points, seam gap max %.3g\n",
            m.stats.segments, m.stats.joints, m.stats.ball_joints, m.stats.sharp_joints, m.stats.unfitted_joints,
            m.stats.cap_intersections_found, m.stats.cap_intersections_unhandled, m.stats.branch_points,
            m.stats.seam_gap_max);
    double depth = 0;
    if (r == MESO_OK && a.relief) {
        depth = a.relief_depth;
        if (depth <= 0) {
            double sum = 0;
            for (uint32_t s = 0; s < m.segment_count; ++s)
                sum += 0.5 * (m.segments[s].r0 + m.segments[s].r1);
            depth = 0.25 * sum / m.segment_count;
        }
        if (!(depth > 0))
            r = meso_bake_fail(&err, MESO_ERR_INVALID_ARG, 0,
                "--relief needs --relief-depth: every radius is 0, so no default depth");
    }
    if (r == MESO_OK) {
        meso_frusta_relief_params rp = {.depth = depth, .u_repeat = a.relief_repeat};
        r = meso_frusta_object_build(&sk, &m, &rp, &obj, &err);
    }
    if (r == MESO_OK)
        r = meso_frusta_object_encode(&obj, &frus, &fseg, &ball, &err);
    if (r == MESO_OK) {
        meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_FRUSTA};
        memcpy(rec.bbox_min, obj.bbox_min, sizeof(rec.bbox_min));
        memcpy(rec.bbox_max, obj.bbox_max, sizeof(rec.bbox_max));
        snprintf(rec.name, sizeof(rec.name), "%s", base_name(a.in));
        meta = cJSON_CreateObject();
        cJSON_AddStringToObject(meta, "generator", "mesobake " MESO_VERSION_STRING);
        cJSON_AddStringToObject(meta, "command", "frusta");
        cJSON* params = cJSON_AddObjectToObject(meta, "parameters");
        cJSON_AddStringToObject(params, "input", src.kind);
        if (!strcmp(src.kind, "mesh"))
            cJSON_AddNumberToObject(params, "tolerance", src.tolerance);
        cJSON_AddNumberToObject(params, "max_joint_angle", a.max_joint_angle);
        cJSON_AddBoolToObject(params, "minor_axis_fit", !a.no_fit);
        cJSON_AddBoolToObject(params, "keep_cap_intersections", a.keep_caps);
        if (a.relief) {
            cJSON* rl = cJSON_AddObjectToObject(params, "relief");
            cJSON_AddStringToObject(rl, "spec", a.relief);
            cJSON_AddNumberToObject(rl, "depth", depth);
            cJSON_AddNumberToObject(rl, "repeat", a.relief_repeat);
        }
        r = add_input_provenance(cJSON_AddArrayToObject(meta, "inputs"), a.in, &err);
        /* fit_error for skeleton input: how far the §2.2 fit moved the cone
         * radii at the nodes from the input's. */
        const int mesh_in = !strcmp(src.kind, "mesh");
        rep = report_json(&m, &src, mesh_in ? src.fit_error_max : m.stats.radius_change_max,
            mesh_in ? src.fit_error_mean : m.stats.radius_change_mean, &obj);
        report_mesh_warnings(rep);
        bake_chunk chunks[5];
        int count = 0;
        chunks[count++] = (bake_chunk){.desc = {.type = MESO_CHUNK_SKEL, .object = 1, .dims = {obj.node_count, 1, 1}},
            .data = obj.skel, .size = (size_t)obj.node_count * MESO_SKEL_RECORD_SIZE};
        chunks[count++] = (bake_chunk){
            .desc = {.type = MESO_CHUNK_FRUS, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1, .dims = {obj.count, 1, 1}},
            .data = frus, .size = (size_t)obj.count * MESO_FRUS_RECORD_SIZE};
        chunks[count++] = (bake_chunk){
            .desc = {.type = MESO_CHUNK_FSEG, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1, .dims = {obj.count, 1, 1}},
            .data = fseg, .size = (size_t)obj.count * MESO_FSEG_RECORD_SIZE};
        if (obj.ball_count)
            chunks[count++] = (bake_chunk){.desc = {.type = MESO_CHUNK_BALL, .flags = MESO_CHUNK_FLAG_REQUIRED,
                                               .object = 1, .dims = {obj.ball_count, 1, 1}},
                .data = ball, .size = (size_t)obj.ball_count * MESO_BALL_RECORD_SIZE};
        if (a.relief)
            chunks[count++] = (bake_chunk){.desc = {.type = MESO_CHUNK_RELF, .object = 1, .dtype = relief.dtype,
                                               .components = 1, .dims = {relief.dims[0], relief.dims[1], 1}},
                .data = relief.encoded, .size = relief.encoded_size};
        if (r == MESO_OK)
            r = write_meso(a.out, meta, rep, &rec, chunks, count, &file_size, &err);
    }
    const int code = finish_bake(r, &err, a.out, a.report, rep, file_size, t0);
    cJSON_Delete(meta);
    cJSON_Delete(rep);
    free(frus);
    free(fseg);
    free(ball);
    meso_texfn_free(&relief);
    meso_frusta_object_free(&obj);
    meso_frustum_model_free(&m);
    meso_skeleton_free(&sk);
    return code;
}
