/*
 * skeleton_from_mesh_internal.h — what the files of meso_skeleton_from_mesh
 * share (internal, mesoi_ prefix). The decisions and their numbers are in
 * skeleton_from_mesh.h; each file's top says which stage it holds:
 *
 *   skeleton_from_mesh.c   the public distances, the output, the pipeline
 *   skeleton_mesh_checks.c 1. checks and the compact mesh CGAL gets
 *   skeleton_tree.c        2.-4. CGAL's graph to a spanning tree, radii
 *   skeleton_model.c       the union of round-ended frusta and its errors
 *   triangle_grid.c        exact point-to-mesh distance (model -> mesh)
 *   skeleton_radius_fit.c  5. the Levenberg–Marquardt fit
 *   skeleton_simplify.c    5. split, merge: simplification to the tolerance
 */
#ifndef MESO_SKELETON_FROM_MESH_INTERNAL_H
#define MESO_SKELETON_FROM_MESH_INTERNAL_H

#include <stdint.h>

#include "adapters.h" /* meso_cgal_skeleton: a plain struct, compiled without CGAL too */
#include "skeleton_from_mesh.h"
#include "vec3d.h"

/* >>geometry ------------------------------------------------------------ */

/* Parameter of p's projection on segment a -> b, unclamped (0 if a == b). */
static inline double mesoi_seg_param(const double a[3], const double b[3], const double p[3])
{
    double ab[3], ap[3];
    sub3(b, a, ab);
    sub3(p, a, ap);
    const double l2 = dot3(ab, ab);
    return l2 > 0 ? dot3(ap, ab) / l2 : 0;
}

/* Distance from p to the point of a -> b at parameter t. */
static inline double mesoi_dist_at(const double a[3], const double b[3], double t, const double p[3])
{
    const double q[3] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
    return dist3(p, q);
}

/* Distance from p to the segment a -> b. */
static inline double mesoi_dist_segment(const double a[3], const double b[3], const double p[3])
{
    double t = mesoi_seg_param(a, b, p);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return mesoi_dist_at(a, b, t, p);
}

/* >>checks (skeleton_mesh_checks.c) ------------------------------------- */

/* The mesh as CGAL gets it: used vertices only, outward orientation. */
typedef struct mesoi_clean_mesh {
    uint32_t nv, nt;
    double* xyz;    /* 3 * nv */
    uint32_t* tri;  /* 3 * nt, compact indices */
    uint32_t* orig; /* compact -> input vertex index */
    double diag;
    int flipped;
} mesoi_clean_mesh;

/* Everything skeleton_from_mesh.h promises about the input (1.), then the
 * compact copy in `c` (freed with mesoi_clean_mesh_free; zeroed on failure). */
meso_result mesoi_skel_check_and_clean(const meso_mesh* m, mesoi_clean_mesh* c, meso_error* err);
void mesoi_clean_mesh_free(mesoi_clean_mesh* c);

/* >>tree (skeleton_tree.c) ---------------------------------------------- */

/* The working tree: CGAL's nodes 0 .. ncgal-1, then the copies made by
 * cutting cycles. Mesh vertices belong to CGAL nodes (vstart/vlist over
 * ncgal; copies own none). */
typedef struct mesoi_work_tree {
    uint32_t ncgal, n;
    double* pos;       /* 3 * n */
    double* rad;       /* n */
    int32_t* parent;   /* n, -1 for a root */
    uint32_t* src;     /* n: the CGAL node a node is (a copy's original) */
    uint32_t* cstart;  /* n + 1: children of i are child[cstart[i] .. cstart[i+1]) */
    uint32_t* child;
    uint32_t* vstart;  /* ncgal + 1 */
    uint32_t* vlist;   /* mesh vertices, grouped by node */
    uint32_t* adj_start; /* ncgal + 1: CGAL graph adjacency (deduplicated) */
    uint32_t* adj;
    uint32_t roots, cycles, unmapped, edges;
} mesoi_work_tree;

/* CGAL's skeleton `cs` (non-empty) to the working tree `w` (zeroed by the
 * caller; freed with mesoi_work_tree_free even on failure): the graph and
 * the correspondence (2.), per-node radii (4.), the spanning tree (3.). */
meso_result mesoi_work_tree_from_cgal(const mesoi_clean_mesh* c, const meso_cgal_skeleton* cs, mesoi_work_tree* w,
                                      meso_error* err);
void mesoi_work_tree_free(mesoi_work_tree* w);

static inline uint32_t mesoi_tree_degree(const mesoi_work_tree* w, uint32_t i)
{
    return w->cstart[i + 1] - w->cstart[i] + (w->parent[i] >= 0);
}

/* >>model (skeleton_model.c) -------------------------------------------- */

/* The union of round-ended frusta as pieces: a ball per node, a truncated
 * cone per segment, each with a bounding sphere (centre c, radius bound). */
typedef struct mesoi_piece {
    double a[3], b[3];
    double ra, rb;
    double c[3], bound;
    int ball;
    uint32_t node; /* the ball's node, or the segment's child end */
} mesoi_piece;

typedef struct mesoi_model {
    mesoi_piece* p;
    uint32_t n;
} mesoi_model;

/* Room for the pieces of n nodes (2 n); md->p is freed with free(). */
meso_result mesoi_model_alloc(uint32_t n, mesoi_model* md, meso_error* err);
/* Pieces of the nodes with keep[i] (all when keep is NULL): x holds 4
 * doubles per node (position, radius), parent[i] the node's parent (< 0:
 * none). `md` must have room for 2 n pieces (mesoi_model_alloc). */
void mesoi_model_fill(const double* x, const int32_t* parent, const uint8_t* keep, uint32_t n, mesoi_model* md);
/* min over pieces of the signed distance; *hint (a piece index) is tried
 * first and updated to the minimiser (neighbouring queries share it). */
double mesoi_model_distance(const mesoi_model* md, const double p[3], uint32_t* hint);
/* Mesh vertices -> model: largest and mean |signed distance|. */
void mesoi_mesh_to_model(const mesoi_clean_mesh* c, const mesoi_model* md, double* emax, double* emean);
/* Model -> mesh: points sampled on the union's boundary at spacing ~h and
 * their exact distance to the mesh; *out_max the largest, *count the points. */
meso_result mesoi_model_to_mesh(const mesoi_clean_mesh* c, const mesoi_model* md, double h, double* out_max,
                                uint32_t* count, meso_error* err);
/* Sample spacing for mesoi_model_to_mesh at tolerance tol. */
double mesoi_sample_spacing(const mesoi_model* md, double tol);

/* >>fit (skeleton_radius_fit.c, skeleton_simplify.c) -------------------- */

/* The least-squares prior's weight, relative to a node's data curvature. */
#define MESO_SKELFIT_PRIOR 1e-2
/* Conjugate-gradient steps per Levenberg–Marquardt step (an inexact step
 * is enough: the outer iteration corrects it). */
#define MESO_SKELFIT_CG_ITERATIONS 100
/* Levenberg–Marquardt steps per refit (it stops earlier once the cost
 * changes by less than 1e-6 relative). */
#define MESO_SKELFIT_LM_ITERATIONS 30

/* The simplified skeleton is a subset of the working tree's nodes ("kept");
 * a segment is named by its child end b (its parent end is sparent[b]) and
 * holds the working nodes between them. Mesh vertices belong to segments
 * through their CGAL node. x holds each node's fitted position and radius
 * (copies mirror their originals, so a cut cycle stays closed). */
typedef struct mesoi_fit_state {
    const mesoi_clean_mesh* c;
    const mesoi_work_tree* w;
    double tol;
    int refit;           /* least-squares positions and radii */
    uint32_t n;          /* working nodes */
    uint8_t* keep;       /* kept (output) nodes */
    uint8_t* fixed;      /* never merged away: the working tree's roots, tips and branch points, copies, their originals */
    uint8_t* nosplit;    /* per child end: no inner node left to split at */
    uint32_t* seg_child; /* per node: child end of the segment holding it (itself when kept) */
    int32_t* sparent;    /* per kept node: kept parent, -1 at a root */
    double* x;           /* 4 per node: position, radius */
    uint32_t* kstart;    /* kept children: kids[kstart[i] .. kstart[i+1]) */
    uint32_t* kids;
    uint32_t* owner;     /* per mesh vertex: its CGAL node */
    uint32_t* vseg;      /* per mesh vertex: child end of its segment; UINT32_MAX: its owner, a lone ball */
    double* verr;        /* per mesh vertex: |distance| to the model */
    uint32_t* vnear;     /* per mesh vertex: node of the model piece nearest to it (ball or child end) */
    double* segerr;      /* per child end: largest verr of its vertices */
    uint32_t* var;       /* per node: index of its unknowns (kept originals), else UINT32_MAX */
    uint32_t* path;      /* scratch, n */
    mesoi_model md;
    /* Least squares scratch, sized for n unknown blocks of 4. */
    double *H, *E, *g, *dx, *r, *z, *d, *q, *xt, *kappa, *L;
    uint32_t* segs; /* child ends of the segments in the current system */
    uint32_t splits, merges;
} mesoi_fit_state;

/* skeleton_radius_fit.c: every vertex to a segment (its CGAL node's, or
 * the nearest at a kept node), and the Levenberg–Marquardt refit of every
 * kept node's position and radius (no-op unless f->refit). */
void mesoi_skel_assign_vertices(mesoi_fit_state* f);
void mesoi_skel_refit(mesoi_fit_state* f, int iterations);

/* skeleton_simplify.c: the state for the working tree `w` (all nodes kept
 * when `all`, else only the fixed ones), and the top-down simplification
 * (or, without `simplify`, only the evaluation). */
meso_result mesoi_fit_state_init(mesoi_fit_state* f, const mesoi_clean_mesh* c, const mesoi_work_tree* w, double tol,
                                 int refit_on, int all, meso_error* err);
void mesoi_fit_state_free(mesoi_fit_state* f);
meso_result mesoi_fit_skeleton(mesoi_fit_state* f, int simplify, meso_error* err);

#endif /* MESO_SKELETON_FROM_MESH_INTERNAL_H */
