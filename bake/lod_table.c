/*
 * lod_table.c — collecting LODS records and writing the one LODS chunk
 * (lod_table.h). The writer checks the records against §7.10 (4921/4922)
 * as it adds the chunk, so a bake cannot emit levels a reader refuses.
 */
#include "lod_table.h"

#include <stdlib.h>
#include <string.h>

#include "meso_layout.h"

meso_result mesoi_lod_table_add(mesoi_lod_table* t, const meso_level_record* rec, meso_error* err)
{
    if (t->count == t->cap) {
        const uint32_t cap = t->cap ? 2 * t->cap : 8;
        meso_level_record* grown = realloc(t->records, sizeof(*grown) * cap);
        if (!grown)
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "LODS: out of memory");
        t->records = grown;
        t->cap = cap;
    }
    t->records[t->count++] = *rec;
    return MESO_OK;
}

static int by_object_lod(const void* a, const void* b)
{
    const meso_level_record* x = a;
    const meso_level_record* y = b;
    if (x->object != y->object)
        return x->object < y->object ? -1 : 1;
    return x->lod < y->lod ? -1 : x->lod > y->lod ? 1 : 0;
}

meso_result mesoi_lod_table_write(const mesoi_lod_table* t, meso_writer* w, meso_error* err)
{
    int coarse = 0;
    for (uint32_t i = 0; i < t->count; ++i)
        coarse |= t->records[i].lod != 0;
    if (!coarse)
        return MESO_OK;
    meso_level_record* sorted = malloc(sizeof(*sorted) * t->count);
    uint8_t* bytes = calloc(t->count, MESO_LODS_RECORD_SIZE);
    meso_result r = sorted && bytes ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "LODS: out of memory");
    if (r == MESO_OK) {
        memcpy(sorted, t->records, sizeof(*sorted) * t->count);
        /* (object, lod) pairs are unique, so qsort's instability cannot show */
        qsort(sorted, t->count, sizeof(*sorted), by_object_lod);
        for (uint32_t i = 0; i < t->count; ++i)
            meso_level_record_encode(&sorted[i], bytes + (size_t)MESO_LODS_RECORD_SIZE * i);
        const meso_chunk_desc d = {.type = MESO_CHUNK_LODS, .dtype = MESO_DTYPE_BYTES, .components = 1,
                                   .dims = {t->count, 1, 1}};
        r = meso_writer_add(w, &d, bytes, (size_t)MESO_LODS_RECORD_SIZE * t->count, err);
    }
    free(sorted);
    free(bytes);
    return r;
}

void mesoi_lod_table_free(mesoi_lod_table* t)
{
    free(t->records);
    memset(t, 0, sizeof(*t));
}
