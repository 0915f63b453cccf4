/*
 * box_grid.h — a hashed uniform grid of axis-aligned boxes that move: the
 * broad phase of the incremental shell checks (shell_checker.c), where a
 * round moves a few dozen of a million offset triangles and asks which
 * boxes meet theirs. Setting an item's box costs the cells it covers;
 * a query costs the cells its box covers plus what is in them.
 */
#ifndef MESO_BOX_GRID_H
#define MESO_BOX_GRID_H

#include <stddef.h>
#include <stdint.h>

typedef struct meso_box_grid meso_box_grid;

/* A grid for items 0..count-1 (none present at first) with cubic cells of
 * edge `cell` (> 0; about the typical box's extent). NULL when out of
 * memory. */
meso_box_grid* meso_box_grid_create(uint32_t count, double cell);
void meso_box_grid_destroy(meso_box_grid* g);

/* Item i's box becomes [lo, hi] (lo <= hi per axis), or, with lo NULL, item
 * i leaves the grid. Returns 0 when out of memory (the grid is then unusable). */
int meso_box_grid_set(meso_box_grid* g, uint32_t i, const double* lo, const double* hi);

/* The items whose boxes meet [lo, hi] (closed: touching counts), each once,
 * appended to (*out, *n) (grown with realloc, capacity *cap). Not
 * thread-safe (it marks items as seen in the grid). Returns 0 when out of
 * memory. */
int meso_box_grid_query(meso_box_grid* g, const double lo[3], const double hi[3], uint32_t** out, size_t* n,
                        size_t* cap);

/* Tests only: the entries linked in all cells (each present item's, once
 * per cell its box covers at its level; nothing else). */
size_t meso_box_grid_linked(const meso_box_grid* g);

#endif /* MESO_BOX_GRID_H */
