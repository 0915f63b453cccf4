/*
 * lod_table.h — the LODS chunk of a bake (internal, FORMAT.md §7.10): each
 * object's level records collected as its levels are made, written as the
 * one file-wide chunk (the writer places it right after OBJT). Every object
 * kind adds its levels here.
 */
#ifndef MESO_LOD_TABLE_H
#define MESO_LOD_TABLE_H

#include <stdint.h>

#include "meso_bake.h"

typedef struct mesoi_lod_table {
    meso_level_record* records;
    uint32_t count, cap;
} mesoi_lod_table; /* zero-initialised = empty */

/* Add one level of an object (copied). */
meso_result mesoi_lod_table_add(mesoi_lod_table* t, const meso_level_record* rec, meso_error* err);

/* The LODS chunk into `w`: the records sorted by object, then lod (stable:
 * the same records in any order give the same bytes). Nothing when the
 * table is empty or holds only lod 0 records (one level per object is what
 * a file without LODS says). */
meso_result mesoi_lod_table_write(const mesoi_lod_table* t, meso_writer* w, meso_error* err);

void mesoi_lod_table_free(mesoi_lod_table* t);

#endif /* MESO_LOD_TABLE_H */
