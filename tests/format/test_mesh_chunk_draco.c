/* test_mesh_chunk_draco.c — the bake's Draco MESH decoder (bake/mesh_chunk.c)
 * as the .meso reader uses it: round trip, and a header whose counts do not
 * match the bitstream is refused with both sets of counts in the message.
 * Skipped (exit 77) in a build without the Draco adapter. */
#undef NDEBUG
#include "meso_file.h"
#include "meso_layout.h"
#include "mesh_chunk.h"

#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if MESO_HAVE_DRACO
/* A tetrahedron: 4 vertices, 4 triangles (12 indices), positions only. */
static void tetrahedron(meso_mesh* m)
{
    static float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static uint32_t idx[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    memset(m, 0, sizeof *m);
    m->vertex_count = 4;
    m->triangle_count = 4;
    m->positions = pos;
    m->indices = idx;
}

static meso_chunk_info info_for(uint64_t stored, uint64_t decoded)
{
    meso_chunk_info c;
    memset(&c, 0, sizeof c);
    c.type = MESO_CHUNK_MESH;
    c.encoding = MESO_ENCODING_DRACO;
    c.stored_size = stored;
    c.decoded_size = decoded;
    c.components = 1;
    c.dims[0] = c.dims[1] = c.dims[2] = 1;
    return c;
}

static void draco_chunk_round_trips(void)
{
    meso_mesh m;
    tetrahedron(&m);
    meso_draco_options opt = {14, 10, 12, 7};
    meso_mesh_chunk mc;
    meso_error e;
    assert(meso_bake_mesh_chunk(&m, &opt, &mc, &e) == MESO_OK && mc.encoding == MESO_ENCODING_DRACO);
    const meso_decoder dec = meso_bake_draco_decoder();
    assert(dec.decode_fn != NULL);
    meso_chunk_info c = info_for(mc.size, mc.decoded_size);
    uint8_t* out = malloc((size_t)mc.decoded_size);
    assert(dec.decode_fn(dec.user, &c, mc.data, mc.size, out, (size_t)mc.decoded_size, &e) == MESO_OK);
    meso_mesh_view v;
    assert(meso_mesh_parse(out, (size_t)mc.decoded_size, &v, &e) == MESO_OK);
    assert(v.layout.vertex_count == 4 && v.layout.index_count == 12);
    free(out);
    free(mc.data);
}

/* The header claims 5 vertices (with a consistent layout and decoded size),
 * the bitstream holds 4: the message must name both, not "0 vertices". */
static void count_mismatch_names_the_bitstream_counts(void)
{
    meso_mesh m;
    tetrahedron(&m);
    meso_draco_options opt = {14, 10, 12, 7};
    meso_mesh_chunk mc;
    meso_error e;
    assert(meso_bake_mesh_chunk(&m, &opt, &mc, &e) == MESO_OK);
    uint8_t* p = (uint8_t*)mc.data;
    meso_mesh_layout l;
    assert(meso_mesh_compute_layout(5, 12, MESO_MESH_ATTR_POSITIONS, &l) == MESO_OK);
    l.quant_bits_position = p[MESO_MESH_OFF_QUANT_POSITION];
    meso_mesh_write_header(&l, p);
    const meso_decoder dec = meso_bake_draco_decoder();
    meso_chunk_info c = info_for(mc.size, l.size);
    uint8_t* out = malloc((size_t)l.size);
    memset(&e, 0, sizeof e);
    meso_result r = dec.decode_fn(dec.user, &c, mc.data, mc.size, out, (size_t)l.size, &e);
    printf("mismatch: %s\n", e.message);
    assert(r == MESO_ERR_CORRUPT && e.code == MESO_ISSUE_MESH_COUNTS);
    assert(strstr(e.message, "holds 4 vertices / 12 indices") != NULL);
    assert(strstr(e.message, "header says 5 / 12") != NULL);

    /* The same through the container: read_chunk passes the message on. */
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = MESO_CHUNK_MESH;
    d.object = 1;
    d.encoding = MESO_ENCODING_DRACO;
    d.decoded_size = l.size;
    assert(meso_writer_add(w, &d, mc.data, mc.size, &e) == MESO_OK);
    size_t need = 0;
    assert(meso_writer_finish(w, NULL, 0, &need) == MESO_OK);
    uint8_t* file = malloc(need);
    assert(meso_writer_finish(w, file, need, &need) == MESO_OK);
    meso_writer_destroy(w);
    meso_open_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.decoders = &dec;
    desc.decoder_count = 1;
    meso_file* f = NULL;
    assert(meso_file_open_memory(file, need, &desc, &f, &e) == MESO_OK);
    assert(meso_file_read_chunk(f, 0, out, (size_t)l.size, &e) == MESO_ERR_CORRUPT);
    assert(e.code == MESO_ISSUE_MESH_COUNTS && strstr(e.message, "holds 4 vertices") != NULL);
    meso_file_close(f);
    free(file);
    free(out);
    free(mc.data);
}
#endif

int main(void)
{
#if MESO_HAVE_DRACO
    draco_chunk_round_trips();
    count_mismatch_names_the_bitstream_counts();
    printf("test_mesh_chunk_draco: ok\n");
    return 0;
#else
    printf("test_mesh_chunk_draco: skipped (no Draco adapter)\n");
    return 77;
#endif
}
