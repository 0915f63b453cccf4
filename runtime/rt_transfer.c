/*
 * rt_transfer.c — a level's data moved to GL in pieces over several
 * meso_rt_stream_upload calls (rt_internal.h, "rt_transfer.c"; issue 14:
 * "an upload step on the GL thread with a per-frame byte budget").
 *
 * Decided: the kinds' loaders stay as they are. While rt->defer is set,
 * the few places that hand data to GL (upload_image and the texture
 * buffers in rt_common.c, rt_cells.c's 3D textures, rt_mesh.c's vertex
 * buffer) make the storage without data and queue a copy of it here. The
 * loader's checks (storage made, every mip level there) run as before.
 * Pieces are bands of whole rows within one slice of a texture level
 * (glTexSubImage2D/3D) and ranges of a buffer (glBufferSubData on
 * GL_COPY_WRITE_BUFFER, which no draw state uses); a texture whose upload
 * builds its mips with glGenerateMipmap gets them once its level 0 is
 * whole (host-built mip levels are queued as levels of their own). Every
 * binding and the unpack state are put back.
 */
#include "rt_internal.h"

#include <string.h>

static int grow(meso_rt* rt, mesoi_transfers* t)
{
    if (t->count < t->cap)
        return 1;
    const uint32_t cap = t->cap ? 2 * t->cap : 8;
    mesoi_transfer* n = mesoi_rt_alloc(rt, sizeof *n * cap);
    if (!n)
        return 0;
    if (t->count)
        memcpy(n, t->item, sizeof *n * t->count);
    mesoi_rt_free(rt, t->item);
    t->item = n;
    t->cap = cap;
    return 1;
}

static void queue(meso_rt* rt, const mesoi_transfer* x, const void* data)
{
    mesoi_transfers* t = rt->defer;
    uint8_t* copy = x->size ? mesoi_rt_alloc(rt, x->size) : NULL;
    if ((x->size && !copy) || !grow(rt, t)) {
        mesoi_rt_free(rt, copy);
        t->failed = 1;
        return;
    }
    if (x->size)
        memcpy(copy, data, x->size);
    t->item[t->count] = *x;
    t->item[t->count++].data = copy;
}

void mesoi_defer_texture(meso_rt* rt, GLuint tex, GLenum target, GLint level, const uint32_t dims[3], GLenum format,
                         GLenum type, size_t texel, int mips, const void* data)
{
    const uint32_t depth = target == GL_TEXTURE_3D ? dims[2] : 1;
    const mesoi_transfer x = {.name = tex, .target = target, .level = level, .dims = {dims[0], dims[1], depth},
                              .format = format, .type = type, .mips = mips, .row = texel * dims[0],
                              .size = texel * dims[0] * dims[1] * depth};
    queue(rt, &x, data);
}

void mesoi_defer_buffer(meso_rt* rt, GLuint buf, size_t offset, size_t size, const void* data)
{
    const mesoi_transfer x = {.name = buf, .buffer = 1, .offset = offset, .row = 1, .size = size};
    queue(rt, &x, data);
}

/* Moves up to `bytes` (whole rows, at least one) of texture transfer x. */
static size_t texture_piece(meso_rt* rt, mesoi_transfer* x, size_t bytes)
{
    mesoi_gl* gl = &rt->gl;
    const size_t slice = x->row * x->dims[1];
    const uint32_t z = (uint32_t)(x->done / slice), y = (uint32_t)(x->done % slice / x->row);
    size_t rows = bytes / x->row;
    rows = rows < 1 ? 1 : rows;
    if (rows > x->dims[1] - y)
        rows = x->dims[1] - y; /* a piece stays within its slice */
    const void* src = x->data + x->done;
    if (x->target == GL_TEXTURE_3D)
        gl->TexSubImage3D(GL_TEXTURE_3D, x->level, 0, (GLint)y, (GLint)z, (GLsizei)x->dims[0], (GLsizei)rows, 1,
                          x->format, x->type, src);
    else
        gl->TexSubImage2D(GL_TEXTURE_2D, x->level, 0, (GLint)y, (GLsizei)x->dims[0], (GLsizei)rows, x->format,
                          x->type, src);
    return rows * x->row;
}

uint64_t mesoi_transfers_run(meso_rt* rt, mesoi_transfers* t, uint64_t budget)
{
    mesoi_gl* gl = &rt->gl;
    uint64_t moved = 0;
    GLint prev2 = 0, prev3 = 0, prev_copy = 0;
    gl->GetIntegerv(GL_TEXTURE_BINDING_2D, &prev2);
    gl->GetIntegerv(GL_TEXTURE_BINDING_3D, &prev3);
    gl->GetIntegerv(GL_COPY_WRITE_BUFFER_BINDING, &prev_copy);
    mesoi_unpack unpack;
    mesoi_unpack_default(rt, &unpack);
    enum { MIN_BUFFER_PIECE = 64 << 10 };
    while (t->next < t->count && (budget == 0 || moved < budget || moved == 0)) {
        mesoi_transfer* x = &t->item[t->next];
        const size_t want = budget == 0 ? x->size - x->done : (size_t)(budget > moved ? budget - moved : 0);
        size_t n;
        if (x->buffer) {
            n = want < MIN_BUFFER_PIECE ? MIN_BUFFER_PIECE : want;
            n = n > x->size - x->done ? x->size - x->done : n;
            gl->BindBuffer(GL_COPY_WRITE_BUFFER, x->name);
            gl->BufferSubData(GL_COPY_WRITE_BUFFER, (GLintptr)(x->offset + x->done), (GLsizeiptr)n, x->data + x->done);
        } else {
            gl->BindTexture(x->target, x->name);
            n = x->size ? texture_piece(rt, x, want) : 0;
        }
        x->done += n;
        moved += n;
        if (x->done == x->size) {
            if (!x->buffer && x->mips)
                gl->GenerateMipmap(x->target); /* still bound */
            mesoi_rt_free(rt, x->data);
            x->data = NULL;
            t->next++;
        }
    }
    gl->BindTexture(GL_TEXTURE_2D, (GLuint)prev2);
    gl->BindTexture(GL_TEXTURE_3D, (GLuint)prev3);
    gl->BindBuffer(GL_COPY_WRITE_BUFFER, (GLuint)prev_copy);
    mesoi_unpack_restore(rt, &unpack);
    return moved;
}

void mesoi_transfers_drop(meso_rt* rt, mesoi_transfers* t, uint32_t first)
{
    for (uint32_t k = first; k < t->count; ++k)
        mesoi_rt_free(rt, t->item[k].data);
    if (first < t->count)
        t->count = first;
}

void mesoi_transfers_free(meso_rt* rt, mesoi_transfers* t)
{
    for (uint32_t k = 0; k < t->count; ++k)
        mesoi_rt_free(rt, t->item[k].data);
    mesoi_rt_free(rt, t->item);
    memset(t, 0, sizeof *t);
}
