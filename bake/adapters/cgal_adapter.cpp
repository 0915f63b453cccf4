// cgal_adapter.cpp — CGAL behind extern "C": exact point-in-mesh queries, exact
// triangle intersection counts (shell validation) and mean-curvature-flow
// skeletons (frustum fitting).
// Kernel: exact predicates, inexact constructions (the first two only need
// predicates; the skeleton's Delaunay poles use CGAL's own exact kernel).
// CGAL's CMake defines CGAL_EIGEN3_ENABLED when Eigen is found; meson links
// Eigen with CGAL (bake/meson.build), so it is defined here.
#ifndef CGAL_EIGEN3_ENABLED
#define CGAL_EIGEN3_ENABLED 1
#endif

// >>arena -----------------------------------------------------------------
// CGAL's mean curvature flow orders its edge collapses by handle address
// (a std::set<edge_descriptor> over a Polyhedron_3 whose items are heap
// nodes), so with the default allocator the skeleton depends on the heap's
// state: the same mesh skeletonized twice in one process gave 58 and then 55
// nodes. CGAL's containers take their allocator from CGAL_ALLOCATOR; here it
// is an allocator that, while a skeletonization runs on this thread, serves
// every request from one reserved address range in call order (with
// per-size LIFO reuse), so addresses — and their order — depend only on the
// sequence of requests, which depends only on the input. Outside of it (the
// other adapter functions) it is plain operator new.
#include <cstddef>
#include <map>
#include <new>
#include <vector>

#include <sys/mman.h>

namespace meso_arena {
struct Arena {
    char* base = nullptr;
    std::size_t cap = 0, used = 0;
    std::vector<void*> small[257]; // free blocks of 16 * k bytes, k <= 256
    std::map<std::size_t, std::vector<void*>> large;
};
inline thread_local Arena* active = nullptr;

inline bool owns(const Arena* a, const void* p)
{
    return a && static_cast<const char*>(p) >= a->base && static_cast<const char*>(p) < a->base + a->cap;
}

inline void* allocate(std::size_t bytes)
{
    Arena* a = active;
    if (!a)
        return ::operator new(bytes);
    const std::size_t size = (bytes + 15) / 16 * 16;
    std::vector<void*>& list = size / 16 <= 256 ? a->small[size / 16] : a->large[size];
    if (!list.empty()) {
        void* p = list.back();
        list.pop_back();
        return p;
    }
    if (size > a->cap - a->used)
        throw std::bad_alloc();
    void* p = a->base + a->used;
    a->used += size;
    return p;
}

inline void deallocate(void* p, std::size_t bytes) noexcept
{
    Arena* a = active;
    if (!owns(a, p)) {
        ::operator delete(p);
        return;
    }
    const std::size_t size = (bytes + 15) / 16 * 16;
    try {
        (size / 16 <= 256 ? a->small[size / 16] : a->large[size]).push_back(p);
    } catch (...) {
        // the block is lost until the arena goes; harmless
    }
}

// Reserves the range (address space only: pages are committed on first
// touch) and makes it this thread's arena until destroyed. Everything
// allocated from it must be freed before then.
struct Scope {
    Arena arena;
    explicit Scope(std::size_t reserve)
    {
        void* p = mmap(nullptr, reserve, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
        if (p == MAP_FAILED)
            throw std::bad_alloc();
        arena.base = static_cast<char*>(p);
        arena.cap = reserve;
        active = &arena;
    }
    ~Scope()
    {
        active = nullptr;
        munmap(arena.base, arena.cap);
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;
};

template <class T> struct Allocator {
    typedef T value_type;
    Allocator() noexcept {}
    template <class U> Allocator(const Allocator<U>&) noexcept {}
    T* allocate(std::size_t n) { return static_cast<T*>(meso_arena::allocate(n * sizeof(T))); }
    void deallocate(T* p, std::size_t n) noexcept { meso_arena::deallocate(p, n * sizeof(T)); }
};
template <class T, class U> bool operator==(const Allocator<T>&, const Allocator<U>&) { return true; }
template <class T, class U> bool operator!=(const Allocator<T>&, const Allocator<U>&) { return false; }
} // namespace meso_arena
#define CGAL_ALLOCATOR(T) meso_arena::Allocator<T>
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/extract_mean_curvature_flow_skeleton.h>

#include <boost/iterator/function_output_iterator.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <memory>
#include <new>
#include <thread>
#include <unordered_set>
#include <utility>
#include <vector>

#include "adapters.h"

namespace {
typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Mesh;
typedef CGAL::Side_of_triangle_mesh<Mesh, K> Side;
} // namespace

struct meso_cgal_inside {
    Mesh mesh;
    std::unique_ptr<Side> side;
};

extern "C" meso_result meso_cgal_inside_create(const meso_mesh* m, meso_cgal_inside** out, meso_error* err)
{
    *out = nullptr;
    try {
        std::unique_ptr<meso_cgal_inside> t(new meso_cgal_inside());
        std::vector<Mesh::Vertex_index> vs;
        vs.reserve(m->vertex_count);
        for (uint32_t i = 0; i < m->vertex_count; ++i)
            vs.push_back(t->mesh.add_vertex(Point(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2])));
        for (uint32_t f = 0; f < m->triangle_count; ++f) {
            const uint32_t* ix = m->indices + 3 * f;
            if (ix[0] >= m->vertex_count || ix[1] >= m->vertex_count || ix[2] >= m->vertex_count)
                return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "triangle %u: index out of range", f);
            if (t->mesh.add_face(vs[ix[0]], vs[ix[1]], vs[ix[2]]) == Mesh::null_face())
                return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "triangle %u: non-manifold, CGAL cannot add it", f);
        }
        if (!CGAL::is_closed(t->mesh))
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "mesh is not closed: point-in-mesh is undefined");
        t->side.reset(new Side(t->mesh));
        *out = t.release();
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "CGAL: out of memory");
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: unknown exception");
    }
}

extern "C" meso_result meso_cgal_inside_query(const meso_cgal_inside* t, const double* xyz, size_t count,
                                              int8_t* side, meso_error* err)
{
    try {
        for (size_t i = 0; i < count; ++i) {
            CGAL::Bounded_side s = (*t->side)(Point(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]));
            side[i] = s == CGAL::ON_BOUNDED_SIDE ? 1 : s == CGAL::ON_UNBOUNDED_SIDE ? -1 : 0;
        }
        return MESO_OK;
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: unknown exception");
    }
}

extern "C" void meso_cgal_inside_destroy(meso_cgal_inside* t)
{
    delete t;
}

// >>intersections --------------------------------------------------------
// Exact triangle-triangle intersection counts (issue #4: shell validation).
// Same kernel: do_intersect and coplanar_orientation are predicates, exact on
// the double coordinates the caller gives.
namespace {
typedef K::Triangle_3 Triangle;
typedef K::Segment_3 Segment;
typedef CGAL::Box_intersection_d::Box_with_info_d<double, 3, uint64_t, CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>
    Box;

// One embedding of an indexed triangle set.
struct Soup {
    const double* xyz;
    const uint32_t* idx;
    Point point(uint32_t v) const { return Point(xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]); }
    bool same_point(uint32_t v, const Soup& o) const
    {
        return xyz[3 * v] == o.xyz[3 * v] && xyz[3 * v + 1] == o.xyz[3 * v + 1] && xyz[3 * v + 2] == o.xyz[3 * v + 2];
    }
};

// Zero area: a repeated index or collinear corners (exact).
bool degenerate(const Soup& s, uint32_t t)
{
    const uint32_t* ix = s.idx + 3 * t;
    if (ix[0] == ix[1] || ix[1] == ix[2] || ix[0] == ix[2])
        return true;
    return CGAL::collinear(s.point(ix[0]), s.point(ix[1]), s.point(ix[2]));
}

// Do triangle sa of a and tb of b intersect beyond their shared corners? A
// corner is shared when both use the vertex index and (cross) it has the same
// coordinates in both embeddings. Rules of PMP::self_intersections
// (do_faces_intersect): one shared corner — an opposite edge meets the other
// triangle; two — the four points are coplanar and the third corners lie on
// the same side of the shared edge; three — the same triangle: counts for a
// self test (duplicate face), not for a cross test (a collapsed prism).
bool pair_intersects(const Soup& a, uint32_t sa, const Soup& b, uint32_t tb, bool cross)
{
    const uint32_t* ia = a.idx + 3 * sa;
    const uint32_t* ib = b.idx + 3 * tb;
    int sh_a[3], sh_b[3], n = 0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (ia[i] == ib[j] && (!cross || a.same_point(ia[i], b))) {
                sh_a[n] = i;
                sh_b[n] = j;
                ++n;
            }
    const Point pa[3] = {a.point(ia[0]), a.point(ia[1]), a.point(ia[2])};
    const Point pb[3] = {b.point(ib[0]), b.point(ib[1]), b.point(ib[2])};
    if (n == 0)
        return CGAL::do_intersect(Triangle(pa[0], pa[1], pa[2]), Triangle(pb[0], pb[1], pb[2]));
    if (n == 1) {
        const int i = sh_a[0], j = sh_b[0];
        return CGAL::do_intersect(Triangle(pa[0], pa[1], pa[2]), Segment(pb[(j + 1) % 3], pb[(j + 2) % 3])) ||
               CGAL::do_intersect(Triangle(pb[0], pb[1], pb[2]), Segment(pa[(i + 1) % 3], pa[(i + 2) % 3]));
    }
    if (n == 2) {
        const Point& p = pa[sh_a[0]];
        const Point& q = pa[sh_a[1]];
        const Point& r = pa[3 - sh_a[0] - sh_a[1]];
        const Point& s = pb[3 - sh_b[0] - sh_b[1]];
        return CGAL::coplanar(p, q, r, s) && CGAL::coplanar_orientation(p, q, r, s) == CGAL::POSITIVE;
    }
    return !cross;
}

// Boxes of the non-degenerate triangles t with keep[t] (keep NULL: all);
// info = (set << 32) | triangle. Returns the number of degenerate ones skipped.
uint32_t boxes_of(const Soup& s, uint32_t triangle_count, const uint8_t* keep, uint64_t set, std::vector<Box>& boxes)
{
    uint32_t degenerate_count = 0;
    for (uint32_t t = 0; t < triangle_count; ++t) {
        if (keep && !keep[t])
            continue;
        if (degenerate(s, t)) {
            ++degenerate_count;
            continue;
        }
        const uint32_t* ix = s.idx + 3 * t;
        boxes.push_back(Box(s.point(ix[0]).bbox() + s.point(ix[1]).bbox() + s.point(ix[2]).bbox(), (set << 32) | t));
    }
    return degenerate_count;
}

uint32_t make_boxes(const Soup& s, uint32_t triangle_count, uint64_t set, std::vector<Box>& boxes)
{
    boxes.reserve(triangle_count);
    return boxes_of(s, triangle_count, nullptr, set, boxes);
}

std::vector<const Box*> box_pointers(const std::vector<Box>& boxes)
{
    std::vector<const Box*> p;
    p.reserve(boxes.size());
    for (const Box& b : boxes)
        p.push_back(&b);
    return p;
}

// Self test on the soup (non-manifold input that Surface_mesh refuses).
void soup_self_intersections(const Soup& s, uint32_t triangle_count, uint8_t* flags, meso_cgal_intersection_count* out)
{
    std::vector<Box> boxes;
    out->degenerate_a = make_boxes(s, triangle_count, 0, boxes);
    std::vector<const Box*> p = box_pointers(boxes);
    uint64_t pairs = 0;
    auto cb = [&](const Box* x, const Box* y) {
        const uint32_t f = (uint32_t)x->info(), g = (uint32_t)y->info();
        if (pair_intersects(s, f, s, g, false)) {
            ++pairs;
            if (flags)
                flags[f] = flags[g] = 1;
        }
    };
    CGAL::box_self_intersection_d<CGAL::Sequential_tag>(p.begin(), p.end(), cb, std::ptrdiff_t(2000));
    out->pairs = pairs;
}

bool check_indices(const uint32_t* indices, uint32_t vertex_count, uint32_t triangle_count, meso_error* err)
{
    for (uint64_t j = 0; j < 3 * (uint64_t)triangle_count; ++j)
        if (indices[j] >= vertex_count) {
            meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "triangle %u: index out of range", (unsigned)(j / 3));
            return false;
        }
    return true;
}

meso_result self_intersections(const double* xyz, uint32_t vertex_count, const uint32_t* indices,
                               uint32_t triangle_count, uint8_t* flags, meso_cgal_intersection_count* out,
                               meso_error* err)
{
    try {
        *out = meso_cgal_intersection_count();
        if (!check_indices(indices, vertex_count, triangle_count, err))
            return MESO_ERR_INVALID_ARG;
        const Soup s = {xyz, indices};
        Mesh mesh;
        std::vector<uint32_t> triangle_of; // Face_index -> input triangle
        std::vector<Mesh::Vertex_index> vs;
        vs.reserve(vertex_count);
        for (uint32_t i = 0; i < vertex_count; ++i)
            vs.push_back(mesh.add_vertex(s.point(i)));
        uint32_t repeated = 0;
        for (uint32_t f = 0; f < triangle_count; ++f) {
            const uint32_t* ix = indices + 3 * f;
            if (ix[0] == ix[1] || ix[1] == ix[2] || ix[0] == ix[2]) {
                ++repeated; // Surface_mesh cannot hold it; zero area anyway
                continue;
            }
            const Mesh::Face_index fi = mesh.add_face(vs[ix[0]], vs[ix[1]], vs[ix[2]]);
            if (fi == Mesh::null_face()) {
                soup_self_intersections(s, triangle_count, flags, out); // non-manifold
                return MESO_OK;
            }
            if (triangle_of.size() <= (size_t)fi)
                triangle_of.resize((size_t)fi + 1);
            triangle_of[(size_t)fi] = f;
        }
        uint64_t pairs = 0;
        uint32_t collinear = 0;
        auto count = [&](const std::pair<Mesh::Face_index, Mesh::Face_index>& fp) {
            if (fp.first == fp.second) {
                ++collinear; // PMP reports a degenerate face f as (f, f), and skips it
                return;
            }
            ++pairs;
            if (flags)
                flags[triangle_of[(size_t)fp.first]] = flags[triangle_of[(size_t)fp.second]] = 1;
        };
        CGAL::Polygon_mesh_processing::self_intersections<CGAL::Sequential_tag>(
            mesh, boost::make_function_output_iterator(count));
        out->pairs = pairs;
        out->degenerate_a = repeated + collinear;
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "CGAL: out of memory");
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: unknown exception");
    }
}

meso_result cross_intersections(const double* xyz_a, const double* xyz_b, uint32_t vertex_count,
                                const uint32_t* indices, uint32_t triangle_count, uint8_t* flags_a, uint8_t* flags_b,
                                meso_cgal_intersection_count* out, meso_error* err)
{
    try {
        *out = meso_cgal_intersection_count();
        if (!check_indices(indices, vertex_count, triangle_count, err))
            return MESO_ERR_INVALID_ARG;
        const Soup a = {xyz_a, indices}, b = {xyz_b, indices};
        std::vector<Box> boxes_a, boxes_b;
        out->degenerate_a = make_boxes(a, triangle_count, 0, boxes_a);
        out->degenerate_b = make_boxes(b, triangle_count, 1, boxes_b);
        std::vector<const Box*> pa = box_pointers(boxes_a), pb = box_pointers(boxes_b);
        uint64_t pairs = 0;
        auto cb = [&](const Box* x, const Box* y) {
            if (x->info() >> 32) // the callback order is not relied upon
                std::swap(x, y);
            const uint32_t s = (uint32_t)x->info(), t = (uint32_t)y->info();
            if (pair_intersects(a, s, b, t, true)) {
                ++pairs;
                if (flags_a)
                    flags_a[s] = 1;
                if (flags_b)
                    flags_b[t] = 1;
            }
        };
        CGAL::box_intersection_d<CGAL::Sequential_tag>(pa.begin(), pa.end(), pb.begin(), pb.end(), cb,
                                                       std::ptrdiff_t(2000));
        out->pairs = pairs;
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "CGAL: out of memory");
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: unknown exception");
    }
}
} // namespace

extern "C" meso_result meso_cgal_self_intersections(const double* xyz, uint32_t vertex_count, const uint32_t* indices,
                                                    uint32_t triangle_count, meso_cgal_intersection_count* out,
                                                    meso_error* err)
{
    return self_intersections(xyz, vertex_count, indices, triangle_count, nullptr, out, err);
}

extern "C" meso_result meso_cgal_self_intersections_mark(const double* xyz, uint32_t vertex_count,
                                                         const uint32_t* indices, uint32_t triangle_count,
                                                         uint8_t* flags, meso_cgal_intersection_count* out,
                                                         meso_error* err)
{
    return self_intersections(xyz, vertex_count, indices, triangle_count, flags, out, err);
}

extern "C" meso_result meso_cgal_cross_intersections(const double* xyz_a, const double* xyz_b, uint32_t vertex_count,
                                                     const uint32_t* indices, uint32_t triangle_count,
                                                     meso_cgal_intersection_count* out, meso_error* err)
{
    return cross_intersections(xyz_a, xyz_b, vertex_count, indices, triangle_count, nullptr, nullptr, out, err);
}

extern "C" meso_result meso_cgal_cross_intersections_mark(const double* xyz_a, const double* xyz_b,
                                                          uint32_t vertex_count, const uint32_t* indices,
                                                          uint32_t triangle_count, uint8_t* flags_a, uint8_t* flags_b,
                                                          meso_cgal_intersection_count* out, meso_error* err)
{
    return cross_intersections(xyz_a, xyz_b, vertex_count, indices, triangle_count, flags_a, flags_b, out, err);
}

// >>shell pairs ----------------------------------------------------------
// meso_cgal_shell_pairs: the changed triangles' boxes against all boxes, the
// changed set split over threads (each with its own copy of the box pointers,
// which box_intersection_d reorders), the pairs sorted at the end; every
// triangle (changed NULL) on at most two threads (split_offset_boxes).
namespace {
typedef std::vector<std::pair<uint32_t, uint32_t>> Pair_list;

// One thread's share: the changed boxes [lo, hi) against every top box
// (self) and every base box (cross).
void shell_pairs_part(const Soup& top, const Soup& base, const std::vector<Box>& changed_boxes, size_t lo, size_t hi,
                      const std::vector<Box>& top_boxes, const std::vector<Box>& base_boxes, const uint8_t* changed,
                      Pair_list& self, Pair_list& cross)
{
    std::vector<const Box*> a, b = box_pointers(top_boxes), c = box_pointers(base_boxes);
    for (size_t i = lo; i < hi; ++i)
        a.push_back(&changed_boxes[i]);
    std::vector<const Box*> a2 = a;
    auto on_self = [&](const Box* x, const Box* y) {
        if (x->info() >> 32)
            std::swap(x, y);
        const uint32_t f = (uint32_t)x->info(), g = (uint32_t)y->info();
        // f is changed; a pair of two changed triangles is met twice: keep f < g.
        if (f == g || ((!changed || changed[g]) && g < f))
            return;
        if (pair_intersects(top, f, top, g, false))
            self.push_back(std::make_pair(f, g));
    };
    auto on_cross = [&](const Box* x, const Box* y) {
        if (x->info() >> 32)
            std::swap(x, y);
        const uint32_t s = (uint32_t)x->info(), t = (uint32_t)y->info();
        if (pair_intersects(top, s, base, t, true))
            cross.push_back(std::make_pair(s, t));
    };
    CGAL::box_intersection_d<CGAL::Sequential_tag>(a.begin(), a.end(), b.begin(), b.end(), on_self,
                                                   std::ptrdiff_t(2000));
    CGAL::box_intersection_d<CGAL::Sequential_tag>(a2.begin(), a2.end(), c.begin(), c.end(), on_cross,
                                                   std::ptrdiff_t(2000));
}

// The intersecting pairs (f < g) among the offset boxes p (one self
// sweep), or, with q, between p and q (one bipartite sweep).
void offset_pairs(const Soup& top, std::vector<const Box*>& p, std::vector<const Box*>* q, Pair_list& self)
{
    auto cb = [&](const Box* x, const Box* y) {
        uint32_t f = (uint32_t)x->info(), g = (uint32_t)y->info();
        if (g < f)
            std::swap(f, g);
        if (pair_intersects(top, f, top, g, false))
            self.push_back(std::make_pair(f, g));
    };
    if (q)
        CGAL::box_intersection_d<CGAL::Sequential_tag>(p.begin(), p.end(), q->begin(), q->end(), cb,
                                                       std::ptrdiff_t(2000));
    else
        CGAL::box_self_intersection_d<CGAL::Sequential_tag>(p.begin(), p.end(), cb, std::ptrdiff_t(2000));
}

// The offset boxes in two halves for two threads, with no pair searched
// twice: A the boxes whose lowest x is below s (the median of the lowest
// x's), B the rest. A pair across the halves has a.max_x >= b.min_x >= s,
// so only A's boxes that reach s (`reach`) can meet B's: self(A), self(B)
// and (reach, B) find every pair once.
void split_offset_boxes(const std::vector<Box>& boxes, std::vector<const Box*>& a, std::vector<const Box*>& b,
                        std::vector<const Box*>& reach)
{
    std::vector<double> lows;
    lows.reserve(boxes.size());
    for (const Box& x : boxes)
        lows.push_back(x.min_coord(0));
    if (lows.empty())
        return;
    std::nth_element(lows.begin(), lows.begin() + (std::ptrdiff_t)(lows.size() / 2), lows.end());
    const double split = lows[lows.size() / 2];
    for (const Box& x : boxes) {
        if (x.min_coord(0) < split) {
            a.push_back(&x);
            if (x.max_coord(0) >= split)
                reach.push_back(&x);
        } else {
            b.push_back(&x);
        }
    }
}

// Every intersecting (offset triangle, base triangle) pair.
void full_cross_pairs(const Soup& top, const Soup& base, const std::vector<Box>& top_boxes,
                      const std::vector<Box>& base_boxes, Pair_list& cross)
{
    std::vector<const Box*> a = box_pointers(top_boxes), c = box_pointers(base_boxes);
    auto cb = [&](const Box* x, const Box* y) {
        if ((x->info() >> 32) == 2) // x from the base set: swap to (offset, base)
            std::swap(x, y);
        const uint32_t s = (uint32_t)x->info(), u = (uint32_t)y->info();
        if (pair_intersects(top, s, base, u, true))
            cross.push_back(std::make_pair(s, u));
    };
    CGAL::box_intersection_d<CGAL::Sequential_tag>(a.begin(), a.end(), c.begin(), c.end(), cb, std::ptrdiff_t(2000));
}

// Drop from `boxes` those that cannot meet any of `near`: a box meets another
// only if they share a point, so they share the grid cell of that point; the
// grid's cell is the largest extent of a `near` box. Boxes spanning more than
// 64 cells are kept unexamined. Keeps the order. Why: box_intersection_d
// sorts both sets, and a round changes a few thousand faces of a million.
void near_boxes(const std::vector<Box>& near, std::vector<Box>& boxes)
{
    double cell = 0;
    for (const Box& x : near)
        for (int k = 0; k < 3; ++k)
            cell = std::max(cell, x.max_coord(k) - x.min_coord(k));
    if (near.empty()) {
        boxes.clear();
        return;
    }
    if (!(cell > 0) || !std::isfinite(cell))
        return;
    auto key = [](int64_t i, int64_t j, int64_t k) {
        return (uint64_t)(i * 73856093) ^ (uint64_t)(j * 19349663) ^ (uint64_t)(k * 83492791);
    };
    auto range = [cell](const Box& x, int k, int64_t& lo, int64_t& hi) {
        lo = (int64_t)std::floor(x.min_coord(k) / cell);
        hi = (int64_t)std::floor(x.max_coord(k) / cell);
    };
    std::unordered_set<uint64_t> cells;
    for (const Box& x : near) {
        int64_t lo[3], hi[3];
        for (int k = 0; k < 3; ++k)
            range(x, k, lo[k], hi[k]);
        for (int64_t i = lo[0]; i <= hi[0]; ++i)
            for (int64_t j = lo[1]; j <= hi[1]; ++j)
                for (int64_t k = lo[2]; k <= hi[2]; ++k)
                    cells.insert(key(i, j, k));
    }
    size_t n = 0;
    for (const Box& x : boxes) {
        int64_t lo[3], hi[3];
        for (int k = 0; k < 3; ++k)
            range(x, k, lo[k], hi[k]);
        bool keep = (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1) > 64;
        for (int64_t i = lo[0]; !keep && i <= hi[0]; ++i)
            for (int64_t j = lo[1]; !keep && j <= hi[1]; ++j)
                for (int64_t k = lo[2]; !keep && k <= hi[2]; ++k)
                    keep = cells.count(key(i, j, k)) != 0;
        if (keep)
            boxes[n++] = x;
    }
    boxes.erase(boxes.begin() + (std::ptrdiff_t)n, boxes.end());
}

// work(k) for k = 0 .. parts-1, each on its own thread (the last on this
// one); the first exception any of them threw is rethrown here.
template <class F> void run_parts(size_t parts, F work)
{
    std::vector<std::exception_ptr> failed(parts);
    std::vector<std::thread> pool;
    for (size_t k = 0; k < parts; ++k) {
        auto part = [&, k]() {
            try {
                work(k);
            } catch (...) {
                failed[k] = std::current_exception();
            }
        };
        if (k + 1 < parts)
            pool.emplace_back(part);
        else
            part();
    }
    for (std::thread& th : pool)
        th.join();
    for (const std::exception_ptr& e : failed)
        if (e)
            std::rethrow_exception(e);
}

bool to_c_pairs(Pair_list& l, meso_cgal_pairs* out)
{
    std::sort(l.begin(), l.end());
    out->count = l.size();
    out->pairs = (uint32_t*)malloc(sizeof(uint32_t) * 2 * (l.empty() ? 1 : l.size()));
    if (!out->pairs)
        return false;
    for (size_t i = 0; i < l.size(); ++i) {
        out->pairs[2 * i] = l[i].first;
        out->pairs[2 * i + 1] = l[i].second;
    }
    return true;
}
} // namespace

extern "C" meso_result meso_cgal_shell_pairs(const double* top, const double* base, uint32_t vertex_count,
                                             const uint32_t* indices, uint32_t triangle_count, const uint8_t* changed,
                                             int threads, meso_cgal_pairs* self, meso_cgal_pairs* cross,
                                             meso_error* err)
{
    *self = meso_cgal_pairs();
    *cross = meso_cgal_pairs();
    try {
        if (!check_indices(indices, vertex_count, triangle_count, err))
            return MESO_ERR_INVALID_ARG;
        const Soup t = {top, indices}, b = {base, indices};
        // Set 0: the changed top boxes (tested); set 1: every top box; set 2: base.
        std::vector<Box> changed_boxes, top_boxes, base_boxes;
        if (changed)
            boxes_of(t, triangle_count, changed, 0, changed_boxes);
        boxes_of(t, triangle_count, nullptr, 1, top_boxes);
        boxes_of(b, triangle_count, nullptr, 2, base_boxes);
        if (changed) {
            near_boxes(changed_boxes, top_boxes);
            near_boxes(changed_boxes, base_boxes);
        }
        const size_t n = changed_boxes.size();
        size_t parts = (size_t)std::max(1, std::min(threads, 64));
        std::vector<Pair_list> selfs(parts), crosses(parts);
        if (!changed) {
            // Everything, on at most two threads: the offset boxes' pairs
            // in two halves that share no pair (split_offset_boxes), the
            // offset/base sweep beside the second half. Splitting as the
            // changed boxes are below made each part sort every box again
            // (at 423k the whole search took 1.32 s); one self sweep
            // beside the offset/base sweep left one core idle most of it.
            std::vector<const Box*> ha, hb, reach;
            split_offset_boxes(top_boxes, ha, hb, reach);
            std::vector<const Box*> hb0 = hb; // the sweeps reorder their sequences: one copy per thread
            parts = parts > 1 ? 2 : 1;
            run_parts(parts, [&](size_t k) {
                if (k == 0) {
                    offset_pairs(t, ha, nullptr, selfs[0]);
                    offset_pairs(t, reach, &hb0, selfs[0]);
                }
                if (k == parts - 1) {
                    offset_pairs(t, hb, nullptr, selfs[k]);
                    full_cross_pairs(t, b, top_boxes, base_boxes, crosses[k]);
                }
            });
        } else {
            run_parts(parts, [&](size_t k) {
                shell_pairs_part(t, b, changed_boxes, n * k / parts, n * (k + 1) / parts, top_boxes, base_boxes,
                                 changed, selfs[k], crosses[k]);
            });
        }
        Pair_list all_self, all_cross;
        for (size_t k = 0; k < parts; ++k) {
            all_self.insert(all_self.end(), selfs[k].begin(), selfs[k].end());
            all_cross.insert(all_cross.end(), crosses[k].begin(), crosses[k].end());
        }
        if (!to_c_pairs(all_self, self) || !to_c_pairs(all_cross, cross)) {
            free(self->pairs);
            free(cross->pairs);
            *self = meso_cgal_pairs();
            *cross = meso_cgal_pairs();
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "CGAL: out of memory");
        }
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "CGAL: out of memory");
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: unknown exception");
    }
}

extern "C" meso_result meso_cgal_test_pairs(const double* top, const double* base, uint32_t vertex_count,
                                            const uint32_t* indices, uint32_t triangle_count, const uint32_t* pairs,
                                            size_t count, int cross, int threads, uint8_t* hit, meso_error* err)
{
    try {
        if (!check_indices(indices, vertex_count, triangle_count, err))
            return MESO_ERR_INVALID_ARG;
        for (size_t i = 0; i < 2 * count; ++i)
            if (pairs[i] >= triangle_count)
                return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "CGAL: pair triangle %u out of range",
                                      pairs[i]);
        const Soup t = {top, indices}, b = {base, indices};
        const Soup& other = cross ? b : t;
        // Threads only for enough pairs to pay for starting them.
        const size_t parts = count > 256 ? (size_t)std::max(1, std::min(threads, 64)) : 1;
        run_parts(parts, [&](size_t k) {
            for (size_t i = count * k / parts; i < count * (k + 1) / parts; ++i) {
                const uint32_t f = pairs[2 * i], g = pairs[2 * i + 1];
                hit[i] = !degenerate(t, f) && !degenerate(other, g) && pair_intersects(t, f, other, g, cross);
            }
        });
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "CGAL: out of memory");
    } catch (const std::exception& e) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: %s", e.what());
    } catch (...) {
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: unknown exception");
    }
}

// >>skeleton -------------------------------------------------------------
// Mean curvature flow skeleton (issue #7, frusta from a mesh). Conversion
// only: the graph's vertices, edges and per-vertex input vertices as C arrays.
namespace {
typedef CGAL::Mean_curvature_flow_skeletonization<Mesh> Mcf;

template <class T> T* c_array(size_t n)
{
    T* p = static_cast<T*>(std::malloc(sizeof(T) * (n ? n : 1)));
    if (!p)
        throw std::bad_alloc();
    return p;
}

void skeleton_free(meso_cgal_skeleton* s)
{
    std::free(s->xyz);
    std::free(s->edges);
    std::free(s->corr_offset);
    std::free(s->corr);
    *s = meso_cgal_skeleton();
}
} // namespace

extern "C" meso_result meso_cgal_skeletonize(const double* xyz, uint32_t vertex_count, const uint32_t* indices,
                                             uint32_t triangle_count, const meso_cgal_skeleton_params* params,
                                             meso_cgal_skeleton* out, meso_error* err)
{
    *out = meso_cgal_skeleton();
    try {
        if (!check_indices(indices, vertex_count, triangle_count, err))
            return MESO_ERR_INVALID_ARG;
        Mesh mesh;
        std::vector<Mesh::Vertex_index> vs;
        vs.reserve(vertex_count);
        for (uint32_t i = 0; i < vertex_count; ++i)
            vs.push_back(mesh.add_vertex(Point(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2])));
        for (uint32_t f = 0; f < triangle_count; ++f) {
            const uint32_t* ix = indices + 3 * f;
            if (mesh.add_face(vs[ix[0]], vs[ix[1]], vs[ix[2]]) == Mesh::null_face())
                return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "triangle %u: non-manifold, CGAL cannot add it", f);
        }
        if (!CGAL::is_closed(mesh))
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "mesh is not closed: CGAL cannot skeletonize it");
        // Address space for the flow's meshes and triangulations, committed
        // only as used (measured: 17 MB for the armadillo's 29k triangles,
        // ~0.6 KiB a triangle; reserved: 16 KiB a triangle + 256 MiB).
        meso_arena::Scope arena((std::size_t)16 * 1024 * triangle_count + ((std::size_t)256 << 20));
        Mcf mcf(mesh);
        if (params && params->quality_speed_tradeoff > 0)
            mcf.set_quality_speed_tradeoff(params->quality_speed_tradeoff);
        if (params && params->medially_centered_speed_tradeoff > 0)
            mcf.set_medially_centered_speed_tradeoff(params->medially_centered_speed_tradeoff);
        Mcf::Skeleton g;
        mcf(g);

        const size_t nv = boost::num_vertices(g), ne = boost::num_edges(g);
        if (nv > UINT32_MAX || ne > UINT32_MAX)
            return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "CGAL skeleton too large");
        out->vertex_count = (uint32_t)nv;
        out->edge_count = (uint32_t)ne;
        out->xyz = c_array<double>(3 * nv);
        out->edges = c_array<uint32_t>(2 * ne);
        out->corr_offset = c_array<uint32_t>(nv + 1);
        size_t nc = 0;
        for (size_t v = 0; v < nv; ++v)
            nc += g[v].vertices.size();
        if (nc > UINT32_MAX)
            throw std::bad_alloc();
        out->corr = c_array<uint32_t>(nc);
        nc = 0;
        for (size_t v = 0; v < nv; ++v) {
            const Point& p = g[v].point;
            out->xyz[3 * v] = p.x();
            out->xyz[3 * v + 1] = p.y();
            out->xyz[3 * v + 2] = p.z();
            out->corr_offset[v] = (uint32_t)nc;
            for (const Mesh::Vertex_index& mv : g[v].vertices)
                out->corr[nc++] = (uint32_t)mv.idx();
        }
        out->corr_offset[nv] = (uint32_t)nc;
        size_t e = 0;
        for (auto ei = boost::edges(g); ei.first != ei.second; ++ei.first, ++e) {
            out->edges[2 * e] = (uint32_t)boost::source(*ei.first, g);
            out->edges[2 * e + 1] = (uint32_t)boost::target(*ei.first, g);
        }
        return MESO_OK;
    } catch (const std::bad_alloc&) {
        skeleton_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "CGAL: out of memory");
    } catch (const std::exception& e) {
        skeleton_free(out);
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: %s", e.what());
    } catch (...) {
        skeleton_free(out);
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "CGAL: unknown exception");
    }
}
