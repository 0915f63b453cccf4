/* rt_internal.h — state shared by the runtime's files (internal, mesoi_ prefix). */
#ifndef MESO_RT_INTERNAL_H
#define MESO_RT_INTERNAL_H

#include "meso_rt.h"
#include "rt_gl.h"

/* One uploaded object. The slot index is id & 0xFFFF, the generation
 * id >> 16, so handles to released slots are detected. */
typedef struct mesoi_object {
    uint32_t generation; /* 1..0xFFFF, bumped each time the slot is reused */
    uint32_t live;       /* 0 = slot free */
    uint32_t kind;       /* meso_object_kind */
    GLuint vao, buffer;
    struct mesoi_shell* shell; /* MESO_OBJECT_SHELL only */
    GLsizei index_count;
    uint64_t indices_offset;
    float bbox_min[3], bbox_max[3];
} mesoi_object;

struct meso_rt {
    meso_allocator alloc;
    meso_log_fn log_fn;
    void* log_user;
    mesoi_gl gl;
    int gl_version; /* major*10+minor */
    GLuint mesh_program;
    GLint u_view, u_proj, u_model, u_light_dir, u_albedo;
    GLuint shell_programs[2][MESO_SHELL_TECHNIQUE_COUNT]; /* [stats][technique], compiled on first use */
    GLuint empty_vao;   /* shells draw from gl_VertexID alone */
    GLuint stats_buffer; /* 3 counters (OpenGL 4.3 shader storage) */
    mesoi_object* objects;
    uint32_t object_capacity;
};

/* rt_shell.c */
meso_result mesoi_shell_load(meso_rt* rt, meso_file* f, uint32_t object_id, mesoi_object* o);
void mesoi_shell_release(meso_rt* rt, mesoi_object* o);
meso_result mesoi_shell_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d);
void mesoi_shell_programs_destroy(meso_rt* rt);
/* Index of the finest-level chunk of `type` for `object`, or -1. */
int32_t mesoi_find_chunk(meso_file* f, uint32_t type, uint32_t object);

/* rt_mesh.c */
GLuint mesoi_compile(meso_rt* rt, GLenum type, const char* const* src, int count, const char* name);
GLuint mesoi_link(meso_rt* rt, GLuint vs, GLuint fs, const char* name);
mesoi_object* mesoi_lookup(const meso_rt* rt, meso_rt_object h);
meso_result mesoi_mesh_program_create(meso_rt* rt);
void mesoi_objects_destroy(meso_rt* rt);

void* mesoi_rt_alloc(meso_rt* rt, size_t size);
void mesoi_rt_free(meso_rt* rt, void* p);
/* Log an item with a printf-style detail; silent without a logger. */
void mesoi_log(meso_rt* rt, meso_log_level level, meso_log_item item, const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#endif
